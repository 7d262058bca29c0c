// BVH builder: binned SAH (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"), 32 bins per axis, subtrees built in parallel
// with oneTBB, then flattened depth-first into 32-byte BVHNodes whose two
// children are adjacent (types.h).
#include <algorithm>
#include <atomic>
#include <memory>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include "host/accel/accel.h"
#include "host/core/error.h"
#include "host/prims/prim_host.h"

namespace cr {

namespace {

constexpr int kBins = 32;
constexpr int kDefaultLeaf = 4;
// Below this depth SAH decides; deeper, object-median splits bound the depth
// (<= 32 + log2(n)) so the traversal stack (CR_BVH_STACK = 64) never overflows.
constexpr int kSahDepth = 32;
constexpr std::uint32_t kParallelThreshold = 4096;
// Spatial splits (--bvh-quality high; Stich, Friedrich & Dietrich 2009,
// "Spatial splits in bounding volume hierarchies"): tried where the best
// object split's two boxes overlap by more than kSplitAlpha of the root's
// area, over kSpatialBins planes per axis, within a budget of
// kSplitBudget x the primitives in extra references, shared among subtrees
// in proportion to their sizes (so the tree does not depend on the order
// in which threads consume it).
constexpr int kSpatialBins = 16;  // <= kBins (SahSweep's arrays)
static_assert(kSpatialBins <= kBins);
constexpr float kSplitAlpha = 1e-5f;
constexpr double kSplitBudget = 0.3;

// Four floats (x, y, z and a lane kept at 0) in one register: GCC's and
// clang's vector extension, SSE on x86-64, whatever the target has elsewhere.
typedef float F4 __attribute__((vector_size(16)));
typedef std::int32_t I4 __attribute__((vector_size(16)));

struct Box {
  F4 lo = {INFINITY, INFINITY, INFINITY, 0.0f}, hi = {-INFINITY, -INFINITY, -INFINITY, 0.0f};
  // glm::min(lo, p) and glm::max(hi, p) lane by lane, NaN and signed zeros
  // included: (p < lo) ? p : lo, (hi < p) ? p : hi.
  void Extend(F4 plo, F4 phi)
  {
    lo = plo < lo ? plo : lo;
    hi = hi < phi ? phi : hi;
  }
  void Extend(const Box& b) { Extend(b.lo, b.hi); }
  void Extend(F4 p) { Extend(p, p); }
  float Area() const
  {
    const F4 e = hi - lo;
    return (e[0] < 0.0f) ? 0.0f : 2.0f * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]);
  }
};

struct BuildNode {
  Box box;
  std::unique_ptr<BuildNode> kids[2];
  std::uint32_t first = 0, count = 0;
  std::vector<std::uint32_t> ids;  // a leaf's references (spatial-split builds; else refs[first, first + count))
};

// A reference with its box, moved with it by the partitions (Embree's
// PrimRef): every pass over a node's references reads them in order, not
// through an index into the scene-sized box array (at 10^7 references that
// gather missed the cache on nearly every read). The id rides in lo's
// fourth lane, masked off when the box is read.
struct PrimRef {
  F4 lo, hi;
  F4 Lo() const { return (F4)((I4)lo & I4{-1, -1, -1, 0}); }
  std::uint32_t Id() const { return __builtin_bit_cast(std::uint32_t, lo[3]); }
  F4 Centroid() const { return 0.5f * (Lo() + hi); }
};
static_assert(sizeof(PrimRef) == 32);

// Passes over more references than this split the range over oneTBB's
// threads; min, max and counts combine exactly, so the tree is the same.
constexpr std::uint32_t kParallelPass = 1u << 16;

// The node's box and its centroids' box.
struct Bounds2 {
  Box box, cb;
  void Add(const PrimRef& r)
  {
    box.Extend(r.Lo(), r.hi);
    cb.Extend(r.Centroid());
  }
  void Join(const Bounds2& o)
  {
    box.Extend(o.box);
    cb.Extend(o.cb);
  }
};

// The three axes' bins of a node, filled in one pass. A bin's box is
// written when its first reference arrives (cnt 0 -> 1) and read only where
// cnt > 0, so a node's bins need no initialisation beyond the counts (3 KB
// of boxes per node otherwise).
struct Bins {
  struct Raw {
    F4 lo, hi;
  };
  std::uint32_t cnt[3][kBins] = {};
  Raw bin[3][kBins];
  void Add(int a, int k, F4 lo, F4 hi)
  {
    Box b;
    if (cnt[a][k]++) b = Box{bin[a][k].lo, bin[a][k].hi};
    b.Extend(lo, hi);
    bin[a][k] = {b.lo, b.hi};
  }
  Box BoxOf(int a, int k) const { return Box{bin[a][k].lo, bin[a][k].hi}; }
  void Join(const Bins& o)
  {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < kBins; ++b) {
        if (!o.cnt[a][b]) continue;
        Box x;
        if (cnt[a][b]) x = BoxOf(a, b);
        x.Extend(o.BoxOf(a, b));
        bin[a][b] = {x.lo, x.hi};
        cnt[a][b] += o.cnt[a][b];
      }
  }
};

struct Builder {
  std::vector<PrimRef> refs;
  int maxLeaf = kDefaultLeaf;
  std::atomic<std::uint64_t> nodeCount{0};
  // Spatial-split builds: the scene (to clip primitives), its ranges, the
  // root's area, and the references made by splits.
  const Scene* scene = nullptr;
  PrimRanges ranges{};
  float rootArea = 0.0f;
  std::atomic<std::uint64_t> splitRefs{0};

  // add(acc, b, e) over [begin, end) into `out` (default-initialised),
  // in parallel when large. An out parameter, not a return value: a node's
  // Bins are 3.4 KB, and two return paths defeat the copy elision.
  template <class Acc, class Add>
  void Reduce(Acc& out, std::uint32_t begin, std::uint32_t end, Add add) const
  {
    if (end - begin <= kParallelPass) {
      add(out, begin, end);
      return;
    }
    out = tbb::parallel_reduce(
        tbb::blocked_range<std::uint32_t>(begin, end, kParallelPass / 4), Acc{},
        [&](const tbb::blocked_range<std::uint32_t>& r, Acc acc) {
          add(acc, r.begin(), r.end());
          return acc;
        },
        [](Acc x, const Acc& y) {
          x.Join(y);
          return x;
        });
  }

  // The SAH sweep over m bins in order: boxOf(j) the bin's box, leftN(j)
  // the references it adds to the left side, rightN(j) those it adds to the
  // right side; take(j, cost) for each split after bin j with references on
  // both sides, left to right (cost without the parent's area).
  template <class BoxOf, class LeftN, class RightN, class Take>
  static void SahSweep(int m, BoxOf boxOf, LeftN leftN, RightN rightN, Take take)
  {
    float rightArea[kBins];
    std::uint32_t rightCnt[kBins];
    Box acc;
    std::uint32_t c = 0;
    for (int j = m - 1; j > 0; --j) {
      acc.Extend(boxOf(j));
      c += rightN(j);
      rightArea[j] = acc.Area();
      rightCnt[j] = c;
    }
    acc = Box{};
    c = 0;
    for (int j = 0; j < m - 1; ++j) {
      acc.Extend(boxOf(j));
      c += leftN(j);
      if (c == 0 || rightCnt[j + 1] == 0) continue;
      take(j, acc.Area() * float(c) + rightArea[j + 1] * float(rightCnt[j + 1]));
    }
  }

  // The best binned-SAH object split of refs[begin, end) over the three
  // axes (cost without the parent's area; axis -1: none), with the boxes of
  // its two sides (the spatial-split test measures their overlap).
  struct ObjectSplit {
    float cost = INFINITY;
    int axis = -1, split = -1;
    float scale = 0.0f;
    Box left, right;
  };
  ObjectSplit FindObjectSplit(const PrimRef* span, std::uint32_t n, const Bounds2& nb) const
  {
    const std::uint32_t begin = 0, end = n;
    const Box& cb = nb.cb;
    const F4 ext = cb.hi - cb.lo;
    // Binned SAH over all three axes, binned in one pass.
    float scale[3];
    for (int a = 0; a < 3; ++a) scale[a] = ext[a] > 0.0f ? float(kBins) / ext[a] : 0.0f;
    const F4 sc = {scale[0], scale[1], scale[2], 0.0f};
    Bins bins;
    Reduce(bins, begin, end, [&](Bins& acc, std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) {
        const PrimRef& r = span[i];
        const F4 lo = r.Lo();
        const F4 f = (0.5f * (lo + r.hi) - cb.lo) * sc;
        for (int a = 0; a < 3; ++a) {
          if (ext[a] <= 0.0f) continue;
          const int k = std::min(kBins - 1, static_cast<int>(f[a]));
          acc.Add(a, k, lo, r.hi);
        }
      }
    });
    ObjectSplit best;
    for (int a = 0; a < 3; ++a) {
      if (ext[a] <= 0.0f) continue;
      const std::uint32_t* cnt = bins.cnt[a];
      // The splits after non-empty bins only: a split after an empty bin
      // costs what the split before it costs (the same two sets), and
      // only a strictly lower cost replaces the best, so skipping them
      // chooses the same split as sweeping all kBins - 1.
      int used[kBins], m = 0;
      for (int b = 0; b < kBins; ++b) {  // without a branch: which bins are empty is data
        used[m] = b;
        m += cnt[b] != 0;
      }
      const auto count = [&](int j) { return cnt[used[j]]; };
      SahSweep(
          m, [&](int j) { return bins.BoxOf(a, used[j]); }, count, count,
          [&](int j, float cost) {
            if (cost < best.cost) {
              best.cost = cost;
              best.axis = a;
              best.split = used[j];
            }
          });
    }
    if (best.axis >= 0) {
      best.scale = scale[best.axis];
      for (int b = 0; b < kBins; ++b)
        if (bins.cnt[best.axis][b]) (b <= best.split ? best.left : best.right).Extend(bins.BoxOf(best.axis, b));
    }
    return best;
  }

  // Partitions refs[0, n) by the object split; returns the size of the
  // left side (n / 2, the order kept, when one side would be empty).
  static std::uint32_t PartitionObject(PrimRef* span, std::uint32_t n, const Box& cb, const ObjectSplit& os)
  {
    PrimRef* it = std::partition(span, span + n, [&](const PrimRef& r) {
      int b = std::min(kBins - 1, static_cast<int>((r.Centroid()[os.axis] - cb.lo[os.axis]) * os.scale));
      return b <= os.split;
    });
    const auto mid = static_cast<std::uint32_t>(it - span);
    return mid == 0 || mid == n ? n / 2 : mid;
  }

  // The node's box and centroid box over span[0, n).
  Bounds2 NodeBounds(const PrimRef* span, std::uint32_t n) const
  {
    Bounds2 nb;
    Reduce(nb, 0, n, [&](Bounds2& acc, std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) acc.Add(span[i]);
    });
    return nb;
  }

  // Reference r cut by the plane x[axis] = pos (SplitBounds of its
  // primitive, within r's own box) into its two sides; an empty box: that
  // side has none of it.
  void Split(const PrimRef& r, int axis, float pos, PrimRef& left, PrimRef& right) const
  {
    const F4 rlo = r.Lo();
    Bounds box;
    box.lo = glm::vec3(rlo[0], rlo[1], rlo[2]);
    box.hi = glm::vec3(r.hi[0], r.hi[1], r.hi[2]);
    const std::uint32_t g = r.Id();
    Bounds l, h;
    PrimSplitBounds(*scene, ranges, g, box, axis, pos, l, h);
    const float id = __builtin_bit_cast(float, g);
    left = PrimRef{F4{l.lo.x, l.lo.y, l.lo.z, id}, F4{l.hi.x, l.hi.y, l.hi.z, 0.0f}};
    right = PrimRef{F4{h.lo.x, h.lo.y, h.lo.z, id}, F4{h.hi.x, h.hi.y, h.hi.z, 0.0f}};
  }
  static bool EmptyRef(const PrimRef& r)
  {
    const F4 lo = r.Lo();
    return !(lo[0] <= r.hi[0] && lo[1] <= r.hi[1] && lo[2] <= r.hi[2]);
  }

  // The best spatial split of span[0, n) in `box`: kSpatialBins planes per
  // axis, each reference entering at the bin of its low side and leaving at
  // the bin of its high side, its clipped part added to every bin between
  // (SAH cost without the parent's area, as the object split's).
  struct SpatialSplit {
    float cost = INFINITY;
    int axis = -1;
    float pos = 0.0f;
  };
  static float Plane(const Box& box, int a, int k)
  {
    return k == kSpatialBins ? box.hi[a] : box.lo[a] + float(k) * ((box.hi[a] - box.lo[a]) / float(kSpatialBins));
  }
  SpatialSplit FindSpatialSplit(const PrimRef* span, std::uint32_t n, const Box& box) const
  {
    struct SBins {
      std::uint32_t enter[3][kSpatialBins] = {}, exit[3][kSpatialBins] = {};
      Box box[3][kSpatialBins];
      void Join(const SBins& o)
      {
        for (int a = 0; a < 3; ++a)
          for (int k = 0; k < kSpatialBins; ++k) {
            enter[a][k] += o.enter[a][k];
            exit[a][k] += o.exit[a][k];
            box[a][k].Extend(o.box[a][k]);
          }
      }
    };
    const F4 ext = box.hi - box.lo;
    SBins sb;
    Reduce(sb, 0, n, [&](SBins& acc, std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) {
        const PrimRef& r = span[i];
        const F4 lo = r.Lo();
        for (int a = 0; a < 3; ++a) {
          if (ext[a] <= 0.0f) continue;
          const float inv = float(kSpatialBins) / ext[a];
          const int b0 = std::clamp(static_cast<int>((lo[a] - box.lo[a]) * inv), 0, kSpatialBins - 1);
          const int b1 = std::clamp(static_cast<int>((r.hi[a] - box.lo[a]) * inv), b0, kSpatialBins - 1);
          ++acc.enter[a][b0];
          ++acc.exit[a][b1];
          if (b0 == b1) {
            acc.box[a][b0].Extend(lo, r.hi);
            continue;
          }
          // Cut at each plane in turn: the left part fills bin k, the
          // rest goes on.
          PrimRef rest = r;
          for (int k = b0; k < b1; ++k) {
            PrimRef l, h;
            Split(rest, a, Plane(box, a, k + 1), l, h);
            if (!EmptyRef(l)) acc.box[a][k].Extend(l.Lo(), l.hi);
            if (EmptyRef(h)) break;
            rest = h;
            if (k + 1 == b1) acc.box[a][b1].Extend(rest.Lo(), rest.hi);
          }
        }
      }
    });
    SpatialSplit best;
    for (int a = 0; a < 3; ++a) {
      if (ext[a] <= 0.0f) continue;
      SahSweep(
          kSpatialBins, [&](int k) { return sb.box[a][k]; }, [&](int k) { return sb.enter[a][k]; },
          [&](int k) { return sb.exit[a][k]; },
          [&](int k, float cost) {
            if (cost < best.cost) {
              best.cost = cost;
              best.axis = a;
              best.pos = Plane(box, a, k + 1);
            }
          });
    }
    return best;
  }

  // Spatial-split build (--bvh-quality high): each node owns its references
  // (a split can put one on both sides, clipped to each); a leaf keeps its
  // ids. `budget`: extra references this subtree may still make.
  std::unique_ptr<BuildNode> BuildSpatial(std::vector<PrimRef> v, int depth, double budget)
  {
    auto node = std::make_unique<BuildNode>();
    ++nodeCount;
    const auto n = static_cast<std::uint32_t>(v.size());
    const Bounds2 nb = NodeBounds(v.data(), n);
    node->box = nb.box;
    auto leaf = [&]() {
      std::sort(v.begin(), v.end(), [](const PrimRef& x, const PrimRef& y) { return x.Id() < y.Id(); });
      node->ids.resize(n);
      for (std::uint32_t i = 0; i < n; ++i) node->ids[i] = v[i].Id();
      node->count = n;
      return std::move(node);
    };
    if (n <= 1) return leaf();
    const Box& cb = nb.cb;
    const F4 ext = cb.hi - cb.lo;
    const int axis = ext[0] > ext[1] ? (ext[0] > ext[2] ? 0 : 2) : (ext[1] > ext[2] ? 1 : 2);
    std::vector<PrimRef> left, right;
    bool done = false;
    if (depth < kSahDepth) {
      ObjectSplit os;
      if (ext[axis] > 0.0f) os = FindObjectSplit(v.data(), n, nb);
      SpatialSplit ss;
      if (budget >= 1.0) {
        Box overlap;
        overlap.lo = os.left.lo < os.right.lo ? os.right.lo : os.left.lo;
        overlap.hi = os.left.hi < os.right.hi ? os.left.hi : os.right.hi;
        if (os.axis < 0 || overlap.Area() > kSplitAlpha * rootArea) ss = FindSpatialSplit(v.data(), n, nb.box);
      }
      const float best = std::min(os.cost, ss.cost);
      const float parentArea = node->box.Area();
      const float splitCost = parentArea > 0.0f ? 1.0f + best / parentArea : INFINITY;
      if (!(best < INFINITY) || (n <= static_cast<std::uint32_t>(maxLeaf) && float(n) <= splitCost)) {
        if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
      } else if (ss.cost < os.cost) {
        const int a = ss.axis;
        for (const PrimRef& r : v) {
          if (r.hi[a] <= ss.pos) {
            left.push_back(r);
          } else if (r.Lo()[a] >= ss.pos) {
            right.push_back(r);
          } else {
            PrimRef l, h;
            Split(r, a, ss.pos, l, h);
            if (!EmptyRef(l)) left.push_back(l);
            if (!EmptyRef(h)) right.push_back(h);
          }
        }
        // Within the budget, and each side smaller than the node.
        done = !left.empty() && !right.empty() && left.size() < n && right.size() < n &&
               double(left.size() + right.size()) - double(n) <= budget;
        if (!done) {
          left.clear();
          right.clear();
        }
      }
      if (!done && os.axis >= 0 && !(ss.cost < os.cost)) {
        const std::uint32_t mid = PartitionObject(v.data(), n, cb, os);
        left.assign(v.begin(), v.begin() + mid);
        right.assign(v.begin() + mid, v.end());
        done = true;
      }
    }
    if (!done) {
      // Object median (deep nodes, coinciding centroids, a failed split).
      if (ext[axis] <= 0.0f && n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
      const std::uint32_t mid = n / 2;
      if (ext[axis] > 0.0f)
        std::nth_element(v.begin(), v.begin() + mid, v.end(), [axis](const PrimRef& x, const PrimRef& y) {
          return x.Centroid()[axis] < y.Centroid()[axis];
        });
      left.assign(v.begin(), v.begin() + mid);
      right.assign(v.begin() + mid, v.end());
    }
    const double extra = double(left.size() + right.size()) - double(n);
    splitRefs += static_cast<std::uint64_t>(extra);
    const double rest = std::max(0.0, budget - extra);
    const double shareL = rest * double(left.size()) / double(left.size() + right.size());
    const double shareR = rest - shareL;
    std::vector<PrimRef>().swap(v);
    if (n > kParallelThreshold) {
      tbb::parallel_invoke([&] { node->kids[0] = BuildSpatial(std::move(left), depth + 1, shareL); },
                           [&] { node->kids[1] = BuildSpatial(std::move(right), depth + 1, shareR); });
    } else {
      node->kids[0] = BuildSpatial(std::move(left), depth + 1, shareL);
      node->kids[1] = BuildSpatial(std::move(right), depth + 1, shareR);
    }
    return node;
  }

  std::unique_ptr<BuildNode> Build(std::uint32_t begin, std::uint32_t end, int depth)
  {
    auto node = std::make_unique<BuildNode>();
    ++nodeCount;
    const std::uint32_t n = end - begin;
    const Bounds2 nb = NodeBounds(refs.data() + begin, n);
    node->box = nb.box;
    const Box& cb = nb.cb;
    auto leaf = [&]() {
      node->first = begin;
      node->count = n;
      // group by type
      std::sort(refs.begin() + begin, refs.begin() + end,
                [](const PrimRef& x, const PrimRef& y) { return x.Id() < y.Id(); });
      return std::move(node);
    };
    if (n <= 1) return leaf();

    auto byCentroid = [](int axis) {
      return [axis](const PrimRef& x, const PrimRef& y) { return x.Centroid()[axis] < y.Centroid()[axis]; };
    };
    std::uint32_t mid = begin;
    const F4 ext = cb.hi - cb.lo;
    int axis = ext[0] > ext[1] ? (ext[0] > ext[2] ? 0 : 2) : (ext[1] > ext[2] ? 1 : 2);
    if (ext[axis] <= 0.0f) {
      // All centroids coincide: SAH cannot separate them.
      if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
      mid = begin + n / 2;
    } else if (depth >= kSahDepth) {
      mid = begin + n / 2;
      std::nth_element(refs.begin() + begin, refs.begin() + mid, refs.begin() + end, byCentroid(axis));
    } else {
      const ObjectSplit os = FindObjectSplit(refs.data() + begin, n, nb);
      const float parentArea = node->box.Area();
      const float leafCost = float(n);
      const float splitCost = parentArea > 0.0f ? 1.0f + os.cost / parentArea : INFINITY;
      if (os.axis < 0 || (n <= static_cast<std::uint32_t>(maxLeaf) && leafCost <= splitCost)) {
        if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
        mid = begin + n / 2;
        std::nth_element(refs.begin() + begin, refs.begin() + mid, refs.begin() + end, byCentroid(axis));
      } else {
        mid = begin + PartitionObject(refs.data() + begin, n, cb, os);
      }
    }
    if (n > kParallelThreshold) {
      tbb::parallel_invoke([&] { node->kids[0] = Build(begin, mid, depth + 1); },
                           [&] { node->kids[1] = Build(mid, end, depth + 1); });
    } else {
      node->kids[0] = Build(begin, mid, depth + 1);
      node->kids[1] = Build(mid, end, depth + 1);
    }
    return node;
  }
};

void Store(const BuildNode& b, BVHNode& out)
{
  for (int a = 0; a < 3; ++a) {
    out.bmin[a] = b.box.lo[a];
    out.bmax[a] = b.box.hi[a];
  }
  out.first = b.first;
  out.count = b.count;
}

// Depth-first flattening: children of node i go to two adjacent new slots.
// `refs`: where the leaves of a spatial-split build put their ids (else
// null: the leaves already name their range of the builder's references).
void Flatten(const BuildNode& b, std::uint32_t self, std::vector<BVHNode>& nodes, AccelInfo& info,
             std::vector<std::uint32_t>* refs)
{
  Store(b, nodes[self]);
  if (b.count > 0 || !b.kids[0]) {
    ++info.leaves;
    if (refs) {
      nodes[self].first = static_cast<std::uint32_t>(refs->size());
      refs->insert(refs->end(), b.ids.begin(), b.ids.end());
    }
    return;
  }
  const auto first = static_cast<std::uint32_t>(nodes.size());
  nodes.resize(nodes.size() + 2);
  nodes[self].first = first;
  nodes[self].count = 0;
  Flatten(*b.kids[0], first, nodes, info, refs);
  Flatten(*b.kids[1], first + 1, nodes, info, refs);
}

}  // namespace

BVHData BuildBVH(const Scene& scene, const AccelParams& params, AccelInfo& info)
{
  if (params.bvhLeaf < 0 || params.bvhLeaf > 255)
    throw InputError(fmt::format("--bvh-leaf {} is not in 1..255", params.bvhLeaf));
  const std::string& quality = params.bvhQuality;
  if (!quality.empty() && quality != "medium" && quality != "high")
    throw InputError(fmt::format("--bvh-quality '{}': expected medium or high", quality));
  const bool spatial = quality == "high";
  Builder bld;
  bld.maxLeaf = params.bvhLeaf > 0 ? params.bvhLeaf : kDefaultLeaf;
  const std::uint32_t n = scene.NumUnified();
  bld.refs.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t g = r.begin(); g < r.end(); ++g) {
      const Bounds b = scene.UnifiedBounds(g);
      bld.refs[g] = PrimRef{F4{b.lo.x, b.lo.y, b.lo.z, __builtin_bit_cast(float, g)}, F4{b.hi.x, b.hi.y, b.hi.z, 0.0f}};
    }
  });

  BVHData out;
  if (n == 0) {
    // An empty root leaf whose box no ray enters.
    BVHNode empty{};
    for (int a = 0; a < 3; ++a) {
      empty.bmin[a] = INFINITY;
      empty.bmax[a] = -INFINITY;
    }
    empty.count = 0;
    empty.first = 0;
    out.nodes.push_back(empty);
    out.header.nNodes = 1;
    info.params = fmt::format("leaf={} bins={}", bld.maxLeaf, kBins);
    info.nodes = 1;
    info.bytes = sizeof(BVHNode);
    return out;
  }
  std::unique_ptr<BuildNode> root;
  if (spatial) {
    bld.scene = &scene;
    bld.ranges = scene.Ranges();
    Bounds2 all = bld.NodeBounds(bld.refs.data(), n);
    bld.rootArea = all.box.Area();
    root = bld.BuildSpatial(std::move(bld.refs), 0, kSplitBudget * double(n));
  } else {
    root = bld.Build(0, n, 0);
  }
  out.nodes.reserve(bld.nodeCount.load());
  out.nodes.resize(1);
  if (spatial) {
    out.refs.reserve(n + bld.splitRefs.load());
    Flatten(*root, 0, out.nodes, info, &out.refs);
  } else {
    Flatten(*root, 0, out.nodes, info, nullptr);
    out.refs.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) out.refs[i] = bld.refs[i].Id();
  }
  out.header.nNodes = static_cast<std::uint32_t>(out.nodes.size());
  out.header.nRefs = static_cast<std::uint32_t>(out.refs.size());
  info.nodes = out.nodes.size();
  info.refs = out.refs.size();
  info.emptyLeaves = 0;
  info.bytes = out.nodes.size() * sizeof(BVHNode) + out.refs.size() * sizeof(std::uint32_t);
  info.params = fmt::format("leaf={} bins={}", bld.maxLeaf, kBins);
  if (spatial)
    info.params += fmt::format(" quality=high spatial_bins={} split_refs={}", kSpatialBins, bld.splitRefs.load());
  return out;
}

}  // namespace cr
