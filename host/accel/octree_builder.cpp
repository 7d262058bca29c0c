// Octree builder: adaptive subdivision of the scene cube (Glassner 1984,
// "Space subdivision for fast ray tracing"): a cell is split into its eight
// octants until it holds at most K references; down to depth 10 always, then
// on to depth 20 only where the surface area heuristic finds the split pays
// (kSahStep: a crowded leaf at depth 10, a teapot in a stadium, splits on,
// the rest of the tree is the classic K = 12, D = 10 one). --octree-depth D
// makes D a hard limit instead; --octree-build sah applies the heuristic
// at every level (no K). Subtrees
// are built in parallel with oneTBB and flattened into the layout of
// kernels/types.h (OctreeNode: non-empty children contiguous, in octant order).
//
// Insertion tests each type's shape against the cell (its OverlapsBox,
// host/prims/: exact where it is cheap, conservative otherwise), in double, against the cell grown by kCellPadRel of the
// scene's coordinate magnitude: the traversal computes cell parameters in
// float from rounded planes, so the t it attributes to a cell may differ by a
// few ulps of the coordinates from the exact one; a primitive that meets the
// grown cell is found whichever side of a boundary the rounding puts its hit.
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <memory>
#include <numeric>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "host/accel/accel.h"
#include "host/prims/prim_host.h"
#include "host/core/error.h"

namespace cr {

// The kernel's Octree_Plane, compiled here so that the builder cuts cells at
// exactly the planes the traversal uses.
namespace octree_kernel {
#include "kernels/octree.h"
}  // namespace octree_kernel

namespace {

// Defaults measured with bench/octree_param_sweep.sh (11 SPD scenes, primary
// and shadow rays, scalar, 1 thread): trace time falls from K = 4 to K = 12-16
// and rises again from K = 24; depth 10 is ~12% faster than 8 and as fast as
// 12 with two thirds of its memory and build time.
constexpr int kDefaultLeaf = 12;
constexpr int kDefaultDepth = 10;
// The surface area heuristic (below depth kDefaultDepth by default, at every
// level with --octree-build sah): a node splits where a ray through it pays
// less in its children than in its own tests. Each octant has a quarter of the node's surface, so a ray through
// the node enters it with probability 1/4, paying kSahStep (a node visit,
// in primitive tests) and a test per reference: split where
// (kSahStep * nonEmptyOctants + references in the octants) / 4 < n. A step
// at 12 tests was measured (bench/ab_speed.py, SIMD, SPD scenes, primary and
// diffuse rays): with the heuristic at every level, 2 tests per step made
// 2-6x the nodes and 15-25% slower traces, 12 came within noise of the
// leaf rule (1.04 of its time). Depth up to CR_OCTREE_MAX_DEPTH, cells at
// least kSahMinPads paddings wide (teapot in a stadium, primary rays: 8
// paddings 591 tests per ray, 2 paddings 116, 1 padding 101 with 60% more
// nodes; the padding, which belongs to the scene, not the ray, is then what
// crowds the finest cells).
constexpr double kSahStep = 12.0;
constexpr double kSahMinPads = 2.0;
// A split whose children hold together this many times the node's references
// cannot pay off (a ray crosses 2 of the 8 octants on average, so it would
// meet more references, not fewer), and it is what a cluster of coincident
// primitives does at every level: such a node stays a leaf.
constexpr double kMaxDuplication = 4.0;
// Cell growth for insertion, relative to the scene's coordinate magnitude:
// 2^-19 = 32 float ulps, above the few ulps of the traversal's rounding.
constexpr double kCellPadRel = 0x1p-19;
// With --octree-margin ray the walk widens each cell by the ray's own
// rounding (Octree_TraceRay), and cells grow only by the rounding of the
// builder's double tests: 2^-40 of the coordinates' magnitude.
constexpr double kCellPadRelRay = 0x1p-40;
// Where the root puts the scene's centre (--octree-root): in the middle
// (centre, the classic octree), or at kRootOffset of its side (offset). The
// middle is where every level's mid planes pass: an object at the scene's
// centre, where scenes put what matters, is cut at every level into four or
// eight chains of nodes, each as deep as the object is small (the teapot in
// a stadium: 2.4 chains per packet of primary rays, 40 steps per ray). 0.45
// lies at least a tenth of a cell from every level's planes (0.45 * 2^L
// mod 1 cycles through .2 .4 .8 .6) at the price of a root 1.11 times the
// scene's extent; measured on the SIMD backend, ray margins, one run
// (cellray trace, 1 thread): teapot in a stadium primary 14.5 -> 9.4 ms,
// diffuse 27.3 -> 22.0; a third (the farthest from every plane, 1.5 times
// the extent) 10.1 and 23.9; on the SPD scenes and meshes either way
// (gears 0.82x, balls 1.14x), which the cost below tells apart.
constexpr double kRootOffset = 0.45;
// With --octree-root auto both roots are built and the one with the lower
// expected cost kept (OctreeCost): offset only where it costs at most this
// fraction of the centred root's (the estimate's own noise: SPD scenes whose
// two costs lie within 2% traced 0.93-1.01x as fast offset).
constexpr double kRootAutoGain = 0.9;
// Above this many primitives auto compares the two roots over a sample of
// about this many (every k-th primitive), and builds only the chosen one in
// full: a 10^7-triangle mesh's octree takes 9-15 s to build (bumpy, sponza).
constexpr std::uint32_t kRootSample = 1u << 18;
// Nodes with more references than this split their octants in parallel.
constexpr std::size_t kParallelRefs = 2048;
// References a build may hold (512 MiB as uint32). Primitives that share an
// edge can never be separated: with --octree-leaf 1 every cell along every
// shared edge subdivides down to the depth limit, 2^D cells per edge.
constexpr std::uint64_t kMaxRefs = std::uint64_t(1) << 27;

struct DBox {
  double lo[3], hi[3];
};

struct BuildNode {
  std::vector<std::uint32_t> refs;  // sorted; leaves only
  std::array<std::unique_ptr<BuildNode>, 8> kids;
  std::uint32_t childMask = 0;
};

class Builder {
 public:
  Builder(const Scene& scene, int maxLeaf, int maxDepth, int sahDepth, bool sah, double padRel, double at)
      : scene_(scene),
        maxLeaf_(maxLeaf),
        maxDepth_(maxDepth),
        sahDepth_(sahDepth),
        sah_(sah),
        padRel_(padRel),
        at_(at)
  {
    const std::uint32_t n = scene.NumUnified();
    boxes_.resize(n);
    for (std::uint32_t g = 0; g < n; ++g) {
      Bounds b = scene.UnifiedBounds(g);
      for (int a = 0; a < 3; ++a) {
        boxes_[g].lo[a] = b.lo[a];
        boxes_[g].hi[a] = b.hi[a];
      }
    }
  }

  OctreeHeader header{};
  double pad = 0.0;
  std::atomic<std::uint64_t> nNodes{0}, nRefs{0}, nUnsplit{0};
  std::atomic<std::uint64_t> nLive{0};  // references held by the tree so far
  std::atomic<int> reached{0};

  // Fits the padded cube around the scene; planes checked with Octree_Plane.
  void FitRoot()
  {
    Bounds wb = scene_.WorldBounds();
    double lo[3], hi[3], ext = 0.0, mag = 0.0;
    for (int a = 0; a < 3; ++a) {
      lo[a] = wb.lo[a];
      hi[a] = wb.hi[a];
      ext = std::max(ext, hi[a] - lo[a]);
      mag = std::max({mag, std::fabs(lo[a]), std::fabs(hi[a])});
    }
    // Margin: primitives keep well inside the root, above its rounding.
    const double margin = ext * 0x1p-10 + mag * 0x1p-17 + 1e-30;
    // The scene's centre lies at at_ of the root's side on every axis (see
    // kRootOffset); the root is then 0.5 / at_ times the scene's extent.
    double size = (ext + 2.0 * margin) * (0.5 / at_);
    for (int attempt = 0;; ++attempt) {
      if (attempt > 64 || !std::isfinite(size)) throw RuntimeError("octree: cannot fit a root cube around the scene");
      header.rootSize = std::nextafter(static_cast<float>(size), INFINITY);
      bool ok = true;
      for (int a = 0; a < 3; ++a) {
        const double mid = 0.5 * (lo[a] + hi[a]);
        header.rootMin[a] = std::nextafter(static_cast<float>(mid - at_ * size), -INFINITY);
        const double p0 = Plane(a, 0, 0), p1 = Plane(a, 0, 1);
        ok = ok && p0 <= lo[a] - 0.5 * margin && p1 >= hi[a] + 0.5 * margin;
      }
      if (ok) break;
      size *= 1.0 + 0x1p-12;
    }
    double coord = 0.0;
    for (int a = 0; a < 3; ++a) coord = std::max({coord, std::fabs(Plane(a, 0, 0)), std::fabs(Plane(a, 0, 1))});
    pad = padRel_ * (coord + double(header.rootSize));
  }

  double Plane(int axis, std::uint32_t level, std::uint32_t i) const
  {
    return double(octree_kernel::Octree_Plane(&header, axis, level, i));
  }

  void Build(BuildNode& node, int level, const std::array<std::uint32_t, 3>& c)
  {
    nNodes.fetch_add(1, std::memory_order_relaxed);
    const std::size_t n = node.refs.size();
    if (level >= maxDepth_) return Leaf(node, level);
    if (!sah_ && n <= static_cast<std::size_t>(maxLeaf_)) return Leaf(node, level);
    // From sahDepth_ on (at once with --octree-build sah), a node splits
    // only where the surface area heuristic finds it pays.
    const bool bySah = sah_ || level >= sahDepth_;
    if (bySah && (n == 0 || std::ldexp(double(header.rootSize), -(level + 1)) < kSahMinPads * pad))
      return Leaf(node, level);

    // Candidate octants from the bounding boxes, then the exact shape test
    // for primitives whose box straddles a mid plane.
    double mid[3];
    DBox cell[8];
    for (int a = 0; a < 3; ++a) mid[a] = Plane(a, level + 1, 2 * c[a] + 1);
    for (int o = 0; o < 8; ++o)
      for (int a = 0; a < 3; ++a) {
        const std::uint32_t ci = 2 * c[a] + ((o >> a) & 1);
        cell[o].lo[a] = Plane(a, level + 1, ci) - pad;
        cell[o].hi[a] = Plane(a, level + 1, ci + 1) + pad;
      }
    std::array<std::vector<std::uint32_t>, 8> lists;
    auto fill = [&](int o) {
      std::vector<std::uint32_t>& out = lists[o];
      for (std::uint32_t g : node.refs) {
        const DBox& b = boxes_[g];
        int nCand = 1;
        bool mine = true;
        for (int a = 0; a < 3; ++a) {
          const bool low = b.lo[a] <= mid[a] + pad, high = b.hi[a] >= mid[a] - pad;
          nCand *= int(low) + int(high);
          mine = mine && (((o >> a) & 1) ? high : low);
        }
        // A primitive of this node whose box meets one octant only lies in it.
        if (mine && (nCand == 1 || Overlaps(g, cell[o]))) out.push_back(g);
      }
    };
    if (n > kParallelRefs)
      tbb::parallel_for(0, 8, fill);
    else
      for (int o = 0; o < 8; ++o) fill(o);

    std::size_t sum = 0;
    for (const auto& l : lists) sum += l.size();
    if (double(sum) >= kMaxDuplication * double(n)) {
      nUnsplit.fetch_add(1, std::memory_order_relaxed);
      return Leaf(node, level);
    }
    if (bySah) {
      int octants = 0;
      for (const auto& l : lists) octants += !l.empty();
      if (!((kSahStep * octants + double(sum)) / 4.0 < double(n))) return Leaf(node, level);
    }
    // Every reference of the node goes to at least one child: sum >= n.
    if (nLive.fetch_add(sum - n, std::memory_order_relaxed) + (sum - n) > kMaxRefs)
      throw RuntimeError(fmt::format("octree: more than {} references with --octree-leaf {} --octree-depth {}: "
                                     "raise the leaf size or lower the depth",
                                     kMaxRefs, maxLeaf_, maxDepth_));
    node.refs.clear();
    node.refs.shrink_to_fit();
    for (int o = 0; o < 8; ++o) {
      if (lists[o].empty()) continue;
      node.childMask |= 1u << o;
      node.kids[o] = std::make_unique<BuildNode>();
      node.kids[o]->refs = std::move(lists[o]);
    }
    auto child = [&](int o) {
      if (!node.kids[o]) return;
      std::array<std::uint32_t, 3> cc;
      for (int a = 0; a < 3; ++a) cc[a] = 2 * c[a] + ((o >> a) & 1);
      Build(*node.kids[o], level + 1, cc);
    };
    if (n > kParallelRefs)
      tbb::parallel_for(0, 8, child);
    else
      for (int o = 0; o < 8; ++o) child(o);
  }

 private:
  void Leaf(BuildNode& node, int level)
  {
    nRefs.fetch_add(node.refs.size(), std::memory_order_relaxed);
    int r = reached.load(std::memory_order_relaxed);
    while (level > r && !reached.compare_exchange_weak(r, level)) {
    }
  }

  // The exact-shape tests shared with the grid (OverlapsBox, host/prims/).
  bool Overlaps(std::uint32_t g, const DBox& cell) const
  {
    return PrimOverlapsBox(scene_, ranges_, g, glm::dvec3(cell.lo[0], cell.lo[1], cell.lo[2]),
                           glm::dvec3(cell.hi[0], cell.hi[1], cell.hi[2]));
  }

  const Scene& scene_;
  const PrimRanges ranges_ = scene_.Ranges();
  int maxLeaf_, maxDepth_, sahDepth_;
  bool sah_;
  double padRel_;
  double at_;
  std::vector<DBox> boxes_;
};

struct Flattener {
  OctreeData& out;
  AccelInfo& info;
  std::uint64_t nEmptyOctants = 0;

  void Flatten(const BuildNode& b, std::uint32_t self, std::uint32_t depth)
  {
    if (b.childMask == 0) {
      out.nodes[self] = OctreeNode{static_cast<std::uint32_t>(out.refs.size()), static_cast<std::uint32_t>(b.refs.size()),
                                   0u, depth};
      out.refs.insert(out.refs.end(), b.refs.begin(), b.refs.end());
      ++info.leaves;
      if (b.refs.empty()) ++info.emptyLeaves;
      return;
    }
    const auto first = static_cast<std::uint32_t>(out.nodes.size());
    const std::uint32_t nKids = static_cast<std::uint32_t>(std::popcount(b.childMask));
    out.nodes.resize(out.nodes.size() + nKids);
    out.nodes[self] = OctreeNode{first, 0u, b.childMask, depth};
    nEmptyOctants += 8 - nKids;
    std::uint32_t k = 0;
    for (int o = 0; o < 8; ++o)
      if (b.kids[o]) Flatten(*b.kids[o], first + k++, depth + 1);
  }
};

}  // namespace

void ForEachOctreeNode(const OctreeData& tree,
                       const std::function<void(std::uint32_t, std::uint32_t, const std::array<std::uint32_t, 3>&)>& fn)
{
  if (tree.nodes.empty()) return;
  auto visit = [&](auto&& self, std::uint32_t ni, std::uint32_t level, const std::array<std::uint32_t, 3>& c) -> void {
    fn(ni, level, c);
    const OctreeNode& nd = tree.nodes[ni];
    std::uint32_t k = 0;
    for (std::uint32_t o = 0; o < 8; ++o)
      if ((nd.childMask >> o) & 1u)
        self(self, nd.first + k++, level + 1u,
             {2u * c[0] + (o & 1u), 2u * c[1] + ((o >> 1) & 1u), 2u * c[2] + ((o >> 2) & 1u)});
  };
  visit(visit, 0u, 0u, {0u, 0u, 0u});
}

std::uint32_t OctreeChainLength(const OctreeData& tree)
{
  if (tree.nodes.empty()) return 0u;
  // References below every node (a node's children follow it in the array).
  std::vector<std::uint32_t> below(tree.nodes.size(), 0u);  // refs are 32-bit indices: so are their counts
  for (std::size_t i = tree.nodes.size(); i-- > 0;) {
    const OctreeNode& nd = tree.nodes[i];
    if (nd.childMask == 0u) {
      below[i] = nd.count;
      continue;
    }
    for (std::uint32_t k = 0; k < static_cast<std::uint32_t>(std::popcount(nd.childMask)); ++k)
      below[i] += below[nd.first + k];
  }
  // Down the heaviest child from the root: the longest run of nodes with one
  // interior child.
  std::uint32_t longest = 0, run = 0, ni = 0;
  while (tree.nodes[ni].childMask != 0u) {
    const OctreeNode& nd = tree.nodes[ni];
    std::uint32_t interior = 0, heaviest = nd.first;
    for (std::uint32_t k = 0; k < static_cast<std::uint32_t>(std::popcount(nd.childMask)); ++k) {
      interior += tree.nodes[nd.first + k].childMask != 0u;
      if (below[nd.first + k] > below[heaviest]) heaviest = nd.first + k;
    }
    run = interior == 1u ? run + 1u : 0u;
    longest = std::max(longest, run);
    ni = heaviest;
  }
  return longest;
}

// The surface area heuristic's expected cost of a random ray through the
// scene's box, in primitive tests: every node clipped to the box and weighted
// by the probability that such a ray meets it (its area over the box's), a
// visit to an interior node counted as kSahStep tests, a leaf as its
// references. Measures the tree as the builder's heuristic does.
double OctreeCost(const Scene& scene, const OctreeData& tree)
{
  if (tree.nodes.empty() || scene.NumUnified() == 0) return 0.0;
  const Bounds wb = scene.WorldBounds();
  auto area = [](const double lo[3], const double hi[3]) {
    double e[3];
    for (int a = 0; a < 3; ++a) e[a] = std::max(0.0, hi[a] - lo[a]);
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
  };
  double wlo[3], whi[3];
  for (int a = 0; a < 3; ++a) {
    wlo[a] = wb.lo[a];
    whi[a] = wb.hi[a];
  }
  const double sceneArea = area(wlo, whi);
  if (!(sceneArea > 0.0)) return 0.0;
  double cost = 0.0;
  ForEachOctreeNode(tree, [&](std::uint32_t ni, std::uint32_t level, const std::array<std::uint32_t, 3>& c) {
    const OctreeNode& nd = tree.nodes[ni];
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(wlo[a], double(octree_kernel::Octree_Plane(&tree.header, a, level, c[a])));
      hi[a] = std::min(whi[a], double(octree_kernel::Octree_Plane(&tree.header, a, level, c[a] + 1u)));
    }
    cost += area(lo, hi) / sceneArea * (nd.childMask ? kSahStep : double(nd.count));
  });
  return cost;
}

namespace {

// One octree with its root's centre at `at` of its side (0.5: centred).
struct Candidate {
  OctreeData out;
  AccelInfo info;
  std::uint64_t nUnsplit = 0, nEmptyOctants = 0;
  double pad = 0.0;  // the cells' growth when they took their references
};

// --octree-leaf-box: puts each non-empty leaf's box before its references
// (CR_OCTREE_BOX_WORDS words, kernels/types.h): the union of its
// primitives' bounds (conservative floats) clipped to its cell grown by
// `pad`, as the cell took them, rounded outward. A hit inside the cell lies
// on a primitive of the leaf and in the cell, so in the box. Returns the
// number of boxes.
std::uint64_t AddLeafBoxes(const Scene& scene, OctreeData& tree, double pad)
{
  // The leaves in walk order with their cells, and where each one's box
  // and references go; then the boxes in parallel.
  struct LeafAt {
    std::uint32_t node, level;
    std::array<std::uint32_t, 3> c;
    std::uint64_t at;  // its first word in the new references
  };
  std::vector<LeafAt> leaves;
  std::uint64_t words = 0, boxes = 0;
  ForEachOctreeNode(tree, [&](std::uint32_t ni, std::uint32_t level, const std::array<std::uint32_t, 3>& c) {
    const OctreeNode& nd = tree.nodes[ni];
    if (nd.childMask != 0u) return;
    leaves.push_back({ni, level, c, words});
    boxes += nd.count > 0u;
    words += (nd.count > 0u ? CR_OCTREE_BOX_WORDS : 0u) + nd.count;
  });
  if (words > 0xFFFFFFFFull) throw RuntimeError("octree: the leaf boxes exceed 32-bit reference indices");
  std::vector<std::uint32_t> refs(words);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      const LeafAt& leaf = leaves[k];
      OctreeNode& nd = tree.nodes[leaf.node];
      const std::uint32_t first = nd.first, count = nd.count;
      std::uint64_t at = leaf.at;
      if (count > 0u) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (std::uint32_t i = first; i < first + count; ++i) {
          const Bounds b = scene.UnifiedBounds(tree.refs[i]);
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], double(b.lo[a]));
            hi[a] = std::max(hi[a], double(b.hi[a]));
          }
        }
        for (int a = 0; a < 3; ++a) {
          const double clo = double(octree_kernel::Octree_Plane(&tree.header, a, leaf.level, leaf.c[a])) - pad;
          const double chi = double(octree_kernel::Octree_Plane(&tree.header, a, leaf.level, leaf.c[a] + 1u)) + pad;
          refs[at + a] = std::bit_cast<std::uint32_t>(FloatDown(std::max(lo[a], clo)));
          refs[at + 3 + a] = std::bit_cast<std::uint32_t>(FloatUp(std::min(hi[a], chi)));
        }
        at += CR_OCTREE_BOX_WORDS;
      }
      std::copy(tree.refs.begin() + first, tree.refs.begin() + first + count, refs.begin() + at);
      nd.first = static_cast<std::uint32_t>(at);
    }
  });
  tree.refs = std::move(refs);
  tree.header.nRefs = static_cast<std::uint32_t>(tree.refs.size());
  return boxes;
}

// stride > 1: over every stride-th primitive only (a sample, to compare roots).
Candidate BuildCandidate(const Scene& scene, int maxLeaf, int maxDepth, int sahDepth, bool sah, double padRel,
                         double at, std::uint32_t stride = 1u)
{
  Candidate cand;
  const std::uint32_t n = scene.NumUnified();
  Builder bld(scene, maxLeaf, maxDepth, sahDepth, sah, padRel, at);
  OctreeData& out = cand.out;
  auto root = std::make_unique<BuildNode>();
  if (n == 0) {
    // An empty root leaf over the unit cube.
    bld.header.rootSize = 1.0f;
  } else {
    bld.FitRoot();
    root->refs.resize((n + stride - 1u) / stride);
    bld.nLive = root->refs.size();
    for (std::size_t i = 0; i < root->refs.size(); ++i) root->refs[i] = static_cast<std::uint32_t>(i * stride);
    bld.Build(*root, 0, {0u, 0u, 0u});
  }
  if (bld.nNodes.load() > 0xFFFFFFFFull || bld.nRefs.load() > 0xFFFFFFFFull)
    throw RuntimeError(fmt::format("octree: {} nodes and {} references exceed 32-bit indices", bld.nNodes.load(),
                                   bld.nRefs.load()));

  out.nodes.reserve(bld.nNodes.load() + 1);
  out.refs.reserve(bld.nRefs.load());
  out.nodes.resize(1);
  Flattener fl{out, cand.info};
  fl.Flatten(*root, 0, 0);
  out.header = bld.header;
  out.header.nNodes = static_cast<std::uint32_t>(out.nodes.size());
  out.header.nRefs = static_cast<std::uint32_t>(out.refs.size());
  out.header.maxDepth = static_cast<std::uint32_t>(bld.reached.load());
  cand.nUnsplit = bld.nUnsplit.load();
  cand.nEmptyOctants = fl.nEmptyOctants;
  cand.pad = bld.pad;
  return cand;
}

}  // namespace

OctreeData BuildOctree(const Scene& scene, const AccelParams& params, AccelInfo& info)
{
  if (params.octreeLeaf < 0) throw InputError(fmt::format("--octree-leaf {} must be >= 1", params.octreeLeaf));
  if (params.octreeDepth < 0 || params.octreeDepth > CR_OCTREE_MAX_DEPTH)
    throw InputError(fmt::format("--octree-depth {} is not in 1..{}", params.octreeDepth, CR_OCTREE_MAX_DEPTH));
  const std::string& how = params.octreeBuild;
  if (!how.empty() && how != "leaf" && how != "sah")
    throw InputError(fmt::format("--octree-build '{}': expected sah or leaf", how));
  const bool sah = how == "sah";
  const std::string& mb = params.octreeMailbox;
  if (!mb.empty() && mb != "on" && mb != "off")
    throw InputError(fmt::format("--octree-mailbox '{}': expected on or off", mb));
  const bool mailbox = mb == "on";
  const std::string& margin = params.octreeMargin;
  if (!margin.empty() && margin != "scene" && margin != "ray")
    throw InputError(fmt::format("--octree-margin '{}': expected scene or ray", margin));
  const bool rayMargin = margin == "ray";
  const std::string& lb = params.octreeLeafBox;
  if (!lb.empty() && lb != "on" && lb != "off")
    throw InputError(fmt::format("--octree-leaf-box '{}': expected on or off", lb));
  if (lb == "on" && !rayMargin)
    throw InputError("--octree-leaf-box on needs --octree-margin ray (the classic octree is the baseline, as it was)");
  const bool leafBoxes = rayMargin && lb != "off";
  const int maxLeaf = sah ? 0 : params.octreeLeaf > 0 ? params.octreeLeaf : kDefaultLeaf;
  // An explicit --octree-depth is a hard limit; by default a leaf rule node
  // splits freely down to kDefaultDepth and beyond only by the heuristic.
  const int maxDepth = params.octreeDepth > 0 ? params.octreeDepth : CR_OCTREE_MAX_DEPTH;
  const int sahDepth = params.octreeDepth > 0 ? params.octreeDepth : kDefaultDepth;

  const std::string& rootHow = params.octreeRoot;
  if (!rootHow.empty() && rootHow != "centre" && rootHow != "offset" && rootHow != "auto")
    throw InputError(fmt::format("--octree-root '{}': expected centre, offset or auto", rootHow));
  // Default: auto with the ray's margins, the classic centred root otherwise.
  const std::string root = rootHow.empty() ? (rayMargin ? "auto" : "centre") : rootHow;
  const double padRel = rayMargin ? kCellPadRelRay : kCellPadRel;
  auto build = [&](double at, std::uint32_t stride) {
    return BuildCandidate(scene, maxLeaf, maxDepth, sahDepth, sah, padRel, at, stride);
  };
  const std::uint32_t n = scene.NumUnified();
  std::string rootNote = root == "offset" ? "offset" : "centre";
  Candidate cand;
  if (root == "auto" && n > 0) {
    // Both roots over the scene, or over a sample of kRootSample
    // primitives of a larger one (then the better is built in full).
    const std::uint32_t stride = (n + kRootSample - 1u) / kRootSample;
    Candidate centred = build(0.5, stride), off = build(kRootOffset, stride);
    const double costCentre = OctreeCost(scene, centred.out), costOffset = OctreeCost(scene, off.out);
    const bool takeOffset = costOffset <= kRootAutoGain * costCentre;
    if (stride == 1u)
      cand = std::move(takeOffset ? off : centred);
    else
      cand = build(takeOffset ? kRootOffset : 0.5, 1u);
    rootNote = fmt::format("auto:{} (cost centre {:.1f}, offset {:.1f}{})", takeOffset ? "offset" : "centre",
                           costCentre, costOffset, stride == 1u ? "" : fmt::format(", 1 in {} primitives", stride));
  } else {
    cand = build(root == "offset" ? kRootOffset : 0.5, 1u);
  }
  OctreeData out = std::move(cand.out);
  info.leaves = cand.info.leaves;
  info.emptyLeaves = cand.info.emptyLeaves;
  out.header.flags = (mailbox ? CR_OCTREE_MAILBOX_ON : 0u) | (rayMargin ? CR_OCTREE_MARGIN_RAY : 0u) |
                     (leafBoxes ? CR_OCTREE_LEAF_BOXES : 0u);
  const std::uint64_t nBoxes = leafBoxes ? AddLeafBoxes(scene, out, cand.pad) : 0u;

  if (rayMargin) out.chain = OctreeChainLength(out);
  info.nodes = out.nodes.size();
  info.leaves += cand.nEmptyOctants;
  info.emptyLeaves += cand.nEmptyOctants;
  info.refs = out.refs.size() - nBoxes * CR_OCTREE_BOX_WORDS;
  info.bytes = sizeof(OctreeHeader) + out.nodes.size() * sizeof(OctreeNode) + out.refs.size() * sizeof(std::uint32_t);
  // The classic octree's description is as it was; any other names its root.
  if (!rayMargin && rootHow.empty()) rootNote.clear();
  info.params = fmt::format("{} depth={} reached={} unsplit={}{}{}{}{} (leaves include {} empty octants)",
                            sah ? std::string("sah") : fmt::format("leaf={}", maxLeaf),
                            sah || sahDepth == maxDepth ? fmt::to_string(maxDepth)
                                                        : fmt::format("{}+sah..{}", sahDepth, maxDepth),
                            out.header.maxDepth, cand.nUnsplit, mailbox ? " mailbox=on" : "",
                            rayMargin ? (leafBoxes ? " margin=ray leaf_box=on" : " margin=ray leaf_box=off") : "",
                            rootNote.empty() ? "" : " root=" + rootNote,
                            rayMargin ? fmt::format(" chain={}", out.chain) : std::string(),
                            cand.nEmptyOctants);
  return out;
}

}  // namespace cr
