// CSG solid (NFF extension `csg union|intersection|difference` ... `csg end`,
// docs/FORMATS.md): the host functions of host/prims/prim_host.h. A block's
// leaves are read by their own types' ParseNff (sphere, box, polyhedron,
// quadric: convex solids) and packed into the block's record; every leaf
// statement keeps its primitive id (PrimInfo::part: its index in the
// block). The fp64 reference is analytic: each leaf's own reference roots
// (its span on the ray's line) classified by the kernels' own rule
// (kernels/csg_sweep.h compiled with real = double).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {
namespace csg_fp64 {
#define CR_FP64
#include "kernels/ray.h"
#include "kernels/csg_sweep.h"
#undef CR_FP64
}  // namespace csg_fp64

namespace {

std::uint32_t LeafType(const Csg& c, std::uint32_t i) { return c.leaf[i] & 255u; }
std::uint32_t LeafWord(const Csg& c, std::uint32_t i) { return c.leaf[i] >> 8; }

// f(leaf) on leaf i as its own type's record.
template <class F>
decltype(auto) VisitLeaf(const Csg& c, std::uint32_t i, F&& f)
{
  const std::uint32_t w = LeafWord(c, i);
  switch (LeafType(c, i)) {
    case CR_PRIM_SPHERE: {
      Sphere s;
      csg_fp64::Csg_Sphere(&c, w, &s);
      return f(s);
    }
    case CR_PRIM_BOX: {
      Box b;
      csg_fp64::Csg_Box(&c, w, &b);
      return f(b);
    }
    case CR_PRIM_QUADRIC: {
      Quadric q;
      csg_fp64::Csg_Quadric(&c, w, &q);
      return f(q);
    }
    default: {
      Polyhedron p{};
      csg_fp64::Csg_Polyhedron(&c, w, &p);
      return f(p);
    }
  }
}

// Inside the leaf (the open solid)?
bool Inside(const Sphere& s, const glm::dvec3& x) { return glm::length(x - ref::D3(s.center)) < double(s.radius); }
bool Inside(const Box& b, const glm::dvec3& x)
{
  for (int a = 0; a < 3; ++a)
    if (!(x[a] > double(b.lo[a]) && x[a] < double(b.hi[a]))) return false;
  return true;
}
bool Inside(const Polyhedron& p, const glm::dvec3& x)
{
  const glm::dvec3 l = x - ref::D3(p.center);
  for (std::uint32_t k = 0; k < p.count; ++k)
    if (!(glm::dot(ref::D3(p.plane[k]), l) + double(p.plane[k][3]) < 0.0)) return false;
  return true;
}
// f(x) = x Q x + 2 l x + j about the centre; the solid is where f has the
// sign opposite to Q's (Q is definite: an ellipsoid, ParseNff).
double QuadricValue(const Quadric& q, const glm::dvec3& x)
{
  const glm::dvec3 l = x - ref::D3(q.center);
  double Q[6];
  for (int e = 0; e < 6; ++e) Q[e] = q.q[e];
  return Q[0] * l.x * l.x + Q[1] * l.y * l.y + Q[2] * l.z * l.z +
         2.0 * (Q[3] * l.x * l.y + Q[4] * l.x * l.z + Q[5] * l.y * l.z) +
         2.0 * (double(q.l[0]) * l.x + double(q.l[1]) * l.y + double(q.l[2]) * l.z) + double(q.j);
}
bool Inside(const Quadric& q, const glm::dvec3& x)
{
  const double f = QuadricValue(q, x);
  return q.q[0] > 0.0f ? f < 0.0 : f > 0.0;
}

// Is x inside the solid (its leaves' open interiors combined)?
bool Member(const Csg& c, const glm::dvec3& x)
{
  std::uint32_t mask = 0;
  for (std::uint32_t i = 0; i < c.nLeaves; ++i)
    if (VisitLeaf(c, i, [&](const auto& leaf) { return Inside(leaf, x); })) mask |= 1u << i;
  std::uint32_t prog[CR_CSG_MAX_NODES];
  const std::uint32_t all = c.nLeaves >= 32 ? ~0u : (1u << c.nLeaves) - 1u;
  return csg_fp64::Csg_EvalProgram(prog, csg_fp64::Csg_Fold(&c, all, 0u, prog), mask) != 0;
}

// The signed distance of leaf i at x (negative inside; exact for the
// sphere and box, a bound for the others, from their RefDistance).
double LeafSigned(const Csg& c, std::uint32_t i, const glm::dvec3& x)
{
  return VisitLeaf(c, i, [&](const auto& leaf) {
    const double d = RefDistance(leaf, x);
    return Inside(leaf, x) ? -d : d;
  });
}

// The expression on signed distances (union min, intersection max,
// difference max(a, -b)): a value whose magnitude is at most the distance
// to the solid's surface; *active: the leaf whose distance it is and
// *negated whether it enters negated (a subtrahend).
double SignedDistance(const Csg& c, const glm::dvec3& x, std::uint32_t* active = nullptr, bool* negated = nullptr)
{
  struct Item {
    double d;
    std::uint32_t leaf;
    bool neg;
  };
  std::vector<Item> st;
  for (std::uint32_t k = 0; k < c.nNodes; ++k) {
    const std::uint32_t n = csg_fp64::Csg_Node(&c, k);
    if (n < CR_CSG_UNION) {
      st.push_back({LeafSigned(c, n, x), n, false});
      continue;
    }
    Item b = st.back();
    st.pop_back();
    Item a = st.back();
    st.pop_back();
    if (n == CR_CSG_DIFFERENCE) b = {-b.d, b.leaf, !b.neg};
    const bool takeA = n == CR_CSG_UNION ? a.d <= b.d : a.d >= b.d;
    st.push_back(takeA ? a : b);
  }
  if (active) *active = st.back().leaf;
  if (negated) *negated = st.back().neg;
  return st.back().d;
}

}  // namespace

const char* PrimTypeName(PrimTag<Csg>) { return "csg"; }

Bounds FloatBounds(const Csg& c) { return StoredBounds(c); }

void SplitBounds(const Csg& c, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  SplitBox(Intersect(FloatBounds(c), box), axis, pos, left, right);
}

// The solid's surface lies on its leaves' surfaces: a cell that meets none
// of them meets none of it.
bool OverlapsBox(const Csg& c, const glm::dvec3& lo, const glm::dvec3& hi)
{
  if (!StoredBoundsMeet(c, lo, hi)) return false;
  for (std::uint32_t i = 0; i < c.nLeaves; ++i)
    if (VisitLeaf(c, i, [&](const auto& leaf) { return OverlapsBox(leaf, lo, hi); })) return true;
  return false;
}

double Scale(const Csg& c)
{
  double s = 0.0;
  for (std::uint32_t i = 0; i < c.nLeaves; ++i) s = std::max(s, VisitLeaf(c, i, [](const auto& leaf) { return Scale(leaf); }));
  return s;
}

// The hit's leaf (u) at the point, its normal turned where it bounds the
// solid from outside (v = 1: a subtrahend's surface).
LocalSurface SurfaceAt(const Scene& scene, const Csg& c, std::uint32_t, const glm::dvec3& pApprox, double u, double v)
{
  const std::uint32_t i = std::min(static_cast<std::uint32_t>(std::max(u, 0.0)), c.nLeaves - 1);
  LocalSurface ls = VisitLeaf(c, i, [&](const auto& leaf) { return SurfaceAt(scene, leaf, 0, pApprox, 0.0, 0.0); });
  if (v > 0.5) {
    ls.ng = -ls.ng;
    ls.ns = -ls.ns;
  }
  return ls;
}

void RefBounds(const Csg& c, glm::dvec3& lo, glm::dvec3& hi) { StoredRefBounds(c, lo, hi); }

// The first crossing of the solid's surface in [tmin, tmax] (one root: the
// leaf of a later one is not known here, and check needs the first); u: its
// leaf, v: whether the leaf's normal turns.
int RefRoots(const ref::DRay& r, const Csg& c, double t[2], double* u, double* v)
{
  ref::DRay line = r;
  line.tmin = -INFINITY;
  line.tmax = INFINITY;
  double t0[CR_CSG_MAX_LEAVES] = {}, t1[CR_CSG_MAX_LEAVES] = {};
  std::uint32_t met = 0;
  for (std::uint32_t i = 0; i < c.nLeaves; ++i) {
    double s[2];
    const int n = VisitLeaf(c, i, [&](const auto& leaf) { return RefRoots(line, leaf, s, nullptr, nullptr); });
    if (n < 2) continue;
    t0[i] = s[0];
    t1[i] = s[1];
    met |= 1u << i;
  }
  std::uint32_t leaf = 0, flip = 0;
  if (!csg_fp64::Csg_Classify(&c, t0, t1, met, r.tmin, r.tmax, &t[0], &leaf, &flip)) return 0;
  if (u) *u = double(leaf);
  if (v) *v = double(flip);
  return 1;
}

int RefPartRoots(const ref::DRay& r, const Csg& c, std::uint32_t part, double t[2])
{
  double u = 0.0;
  return RefRoots(r, c, t, &u, nullptr) > 0 && std::uint32_t(u) == part ? 1 : 0;
}

double RefDistance(const Csg& c, const glm::dvec3& x) { return std::fabs(SignedDistance(c, x)); }

// How near x is to the part of the solid's surface that leaf `part` forms,
// as a lower bound of that distance (check accepts a hit within its
// tolerance of it): the distance to the leaf's surface where the solid's
// membership changes across the leaf at x's foot y there (probed 2^-26 of
// the coordinates to either side: an internal face of a union is no
// surface); elsewhere on the leaf, the membership along its surface can
// only change where another leaf's surface crosses it, so the nearest such
// surface from y (leaves lying in the same plane as the leaf at y, as a
// union's shared faces, excepted) bounds the distance from below.
double RefPartDistance(const Csg& c, std::uint32_t part, const glm::dvec3& x)
{
  if (part >= c.nLeaves) return INFINITY;
  double own = 0.0;
  glm::dvec3 n(0.0);
  bool in = false;
  VisitLeaf(c, part, [&](const auto& leaf) {
    own = RefDistance(leaf, x);
    n = RefNormal(leaf, x);
    in = Inside(leaf, x);
  });
  const glm::dvec3 y = x + (in ? own : -own) * n;
  const double eps = 0x1p-26 * std::max(1.0, MaxAbs(y));
  if (Member(c, y + eps * n) != Member(c, y - eps * n)) return own;
  double nearest = INFINITY;
  for (std::uint32_t j = 0; j < c.nLeaves; ++j) {
    if (j == part) continue;
    VisitLeaf(c, j, [&](const auto& leaf) {
      const double d = RefDistance(leaf, y);
      if (d <= eps && std::fabs(glm::dot(RefNormal(leaf, y), n)) > 1.0 - 1e-9) return;  // the same plane
      nearest = std::min(nearest, d);
    });
  }
  return std::max(own, nearest - own);
}

glm::dvec3 RefNormal(const Csg& c, const glm::dvec3& x)
{
  std::uint32_t leaf = 0;
  bool neg = false;
  SignedDistance(c, x, &leaf, &neg);
  const glm::dvec3 n = VisitLeaf(c, leaf, [&](const auto& l) { return RefNormal(l, x); });
  return neg ? -n : n;
}

void RefBall(const Csg& c, glm::dvec3& mid, double& reach) { StoredRefBall(c, mid, reach); }

void RefNearTimes(const Csg& c, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  for (std::uint32_t i = 0; i < c.nLeaves; ++i)
    VisitLeaf(c, i, [&](const auto& leaf) { RefNearTimes(leaf, r, t0, t1, ts); });
}

namespace {

// A block being read: its record, and the words its leaves take.
struct CsgReader {
  NffStatement& st;
  Scene& scene;
  Csg c{};
  std::uint32_t words = 0;
  std::vector<PrimInfo> leaves;

  void Node(std::uint32_t code, long at)
  {
    if (c.nNodes >= CR_CSG_MAX_NODES)
      st.FailAt(at, fmt::format("'csg': more than {} nodes in one block", CR_CSG_MAX_NODES));
    c.node[c.nNodes / 4] |= code << (8 * (c.nNodes % 4));
    ++c.nNodes;
  }

  float* Words(std::uint32_t n, long at)
  {
    if (words + n > CR_CSG_MAX_WORDS)
      st.FailAt(at, fmt::format("'csg': the block's leaves need more than {} words (a sphere takes 1, a box 2, a quadric "
                                "4, a polyhedron 3 and 1 per plane)",
                                CR_CSG_MAX_WORDS));
    float* w = c.word[words];
    words += n;
    return w;
  }

  // Q definite and the ellipsoid inside its clip box: a closed solid.
  static bool ClosedQuadric(const Quadric& q)
  {
    const glm::dmat3 Q(q.q[0], q.q[3], q.q[4], q.q[3], q.q[1], q.q[5], q.q[4], q.q[5], q.q[2]);
    const double m1 = Q[0][0], m2 = Q[0][0] * Q[1][1] - Q[0][1] * Q[0][1], m3 = glm::determinant(Q);
    const bool pos = m1 > 0.0 && m2 > 0.0 && m3 > 0.0, neg = m1 < 0.0 && m2 > 0.0 && m3 < 0.0;
    if (!pos && !neg) return false;
    const glm::dmat3 Qi = glm::inverse(Q);
    const glm::dvec3 l(q.l[0], q.l[1], q.l[2]);
    const glm::dvec3 x0 = -(Qi * l);
    const double k = glm::dot(l, Qi * l) - double(q.j);
    if (!(pos ? k > 0.0 : k < 0.0)) return false;
    for (int a = 0; a < 3; ++a) {
      const double e = std::sqrt(k * Qi[a][a]);
      if (!(std::fabs(x0[a]) + e < double(q.extent[a]) * (1.0 - 1e-6))) return false;
    }
    return true;
  }

  // A leaf statement `kw` at line `at`: its bounds.
  Bounds Leaf(const std::string& kw, long at, std::uint32_t material)
  {
    if (c.nLeaves >= CR_CSG_MAX_LEAVES)
      st.FailAt(at, fmt::format("'csg': more than {} leaves in one block", CR_CSG_MAX_LEAVES));
    Scene one;
    one.materials.push_back(Material{});
    const auto sub = st.Next(kw, at, material);
    if (!ReadGeometry(*sub, one)) st.FailAt(at, fmt::format("unknown statement '{}' in a 'csg' block", kw));
    const PrimInfo info = one.prims.back();
    const char* what = kw == "s" ? "a sphere" : kw.c_str();
    if (info.kind != PrimKind::kShape || (info.type != CR_PRIM_SPHERE && info.type != CR_PRIM_BOX &&
                                          info.type != CR_PRIM_QUADRIC && info.type != CR_PRIM_POLYHEDRON))
      st.FailAt(at, fmt::format("'csg': '{}' is not a closed solid (a block's operands are s, box, polyhedron, an "
                                "ellipsoidal quadric or a nested csg block)",
                                kw));
    if (info.nPieces == 0 || info.insideVisible)
      st.FailAt(at, fmt::format("'csg': {} of radius 0 or below is not a solid", what));
    const std::uint32_t i = c.nLeaves, first = words;
    Bounds b;
    if (info.type == CR_PRIM_SPHERE) {
      std::memcpy(Words(1, at), &one.spheres[0], sizeof(Sphere));
      b = FloatBounds(one.spheres[0]);
    } else if (info.type == CR_PRIM_BOX) {
      const Box& x = one.boxes[0];
      for (int a = 0; a < 3; ++a)
        if (!(x.lo[a] < x.hi[a])) st.FailAt(at, "'csg': a flat box is not a solid");
      std::memcpy(Words(2, at), &x, sizeof(Box));
      b = FloatBounds(x);
    } else if (info.type == CR_PRIM_QUADRIC) {
      if (!ClosedQuadric(one.quadrics[0]))
        st.FailAt(at, "'csg': the quadric is not a closed solid (an ellipsoid lying inside its clip box)");
      std::memcpy(Words(4, at), &one.quadrics[0], sizeof(Quadric));
      b = FloatBounds(one.quadrics[0]);
    } else {
      const Polyhedron& p = one.polyhedra[0];
      float* w = Words(3 + p.count, at);
      for (int a = 0; a < 3; ++a) {
        w[a] = p.center[a];
        w[4 + a] = p.lo[a];
        w[8 + a] = p.hi[a];
      }
      w[3] = float(p.count);
      std::memcpy(w + 12, p.plane, sizeof(float) * 4 * p.count);
      b = FloatBounds(p);
    }
    c.leaf[i] = info.type | (first << 8);
    ++c.nLeaves;
    PrimInfo leaf = info;
    leaf.type = CR_PRIM_CSG;
    leaf.part = i;
    leaf.nPieces = 1;
    leaves.push_back(leaf);
    Node(i, at);
    return b;
  }

  static std::uint32_t Op(NffStatement& st, const std::string& w, long at)
  {
    if (w == "union") return CR_CSG_UNION;
    if (w == "intersection") return CR_CSG_INTERSECTION;
    if (w == "difference") return CR_CSG_DIFFERENCE;
    st.FailAt(at, fmt::format("'csg': expected union, intersection, difference or end, got '{}'", w));
    return 0;
  }

  // The operands of a block `op` opened at line `open`, up to its `csg
  // end`; an `f` inside applies to the leaves after it in the block.
  Bounds Block(std::uint32_t op, long open, std::uint32_t material)
  {
    Bounds acc;
    int n = 0;
    for (;;) {
      const std::string w = st.Word("an operand or 'csg end'");
      const long at = st.TokenLine();
      Bounds b;
      if (w == "csg") {
        const std::string e = st.Word("'end' or an operation");
        if (e == "end") break;
        b = Block(Op(st, e, st.TokenLine()), at, material);
      } else if (w == "f") {
        material = ReadMaterial(*st.Next("f", at, material), scene);
        continue;
      } else {
        b = Leaf(w, at, material);
      }
      if (n == 0) {
        acc = b;
      } else {
        Node(op, at);
        if (op == CR_CSG_UNION) acc.Extend(b);
        if (op == CR_CSG_INTERSECTION) acc = Intersect(acc, b);
      }
      ++n;
    }
    if (n == 0) st.FailAt(open, fmt::format("'csg' block (line {}) has no operand", open));
    return acc;
  }
};

}  // namespace

// csg union|intersection|difference, its operands (leaf statements, `f`,
// nested blocks), csg end: one record; every leaf statement one primitive
// id, in file order.
bool ParseNff(PrimTag<Csg>, NffStatement& st, Scene& scene)
{
  if (st.keyword != "csg") return false;
  CsgReader rd{st, scene, Csg{}, 0, {}};
  const std::string w = st.Word("union, intersection or difference");
  if (w == "end") st.Fail("'csg end' without an open 'csg' block");
  const Bounds b = rd.Block(CsgReader::Op(st, w, st.TokenLine()), st.line, st.material);
  if (b.Empty()) st.Fail("'csg': the solid is empty (its intersection's operands do not meet)");
  for (int a = 0; a < 3; ++a) {
    rd.c.lo[a] = b.lo[a];
    rd.c.hi[a] = b.hi[a];
  }
  const std::uint32_t firstId = scene.NumPrims();
  const std::uint32_t piece = scene.AddPiece(rd.c, firstId);
  for (PrimInfo info : rd.leaves) {
    info.firstPiece = piece;
    scene.prims.push_back(info);
  }
  return true;
}

}  // namespace cr
