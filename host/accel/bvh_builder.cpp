// BVH builder: binned SAH (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies"), 32 bins per axis, subtrees built in parallel
// with oneTBB, then flattened depth-first into 32-byte BVHNodes whose two
// children are adjacent (types.h).
#include <algorithm>
#include <atomic>
#include <limits>
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

constexpr int kBins = 32;     // bins of a large node (BinsFor)
constexpr int kMinBins = 4;   // and of the smallest
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
  // A subtree built flat (Builder::BuildFlat): sub[0] this node, the rest its
  // descendants, child indices relative to sub.
  std::vector<BVHNode> sub;
};

// A node's box, first and count into its BVHNode.
void StoreNode(const Box& box, std::uint32_t first, std::uint32_t count, BVHNode& out)
{
  for (int a = 0; a < 3; ++a) {
    out.bmin[a] = box.lo[a];
    out.bmax[a] = box.hi[a];
  }
  out.first = first;
  out.count = count;
}

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

// The three axes' bins of a node, filled in one pass. `used` has a bit per
// non-empty bin; a bin's count and box are written when its first reference
// arrives and read only where its bit is set, so a node's bins need no
// initialisation beyond three words (3.4 KB of counts and boxes per node
// otherwise), and the sweeps visit the non-empty bins only: at 10^7
// references most nodes are small, and their fixed costs were most of the
// build.
static_assert(kBins <= 32);
struct Bins {
  struct Raw {
    F4 lo, hi;
  };
  std::uint32_t used[3] = {0u, 0u, 0u};
  std::uint32_t cnt[3][kBins];
  Raw bin[3][kBins];
  void Add(int a, int k, F4 lo, F4 hi)
  {
    const std::uint32_t bit = 1u << k;
    Box b;
    if (used[a] & bit) {
      ++cnt[a][k];
      b = Box{bin[a][k].lo, bin[a][k].hi};
    } else {
      used[a] |= bit;
      cnt[a][k] = 1;
    }
    b.Extend(lo, hi);
    bin[a][k] = {b.lo, b.hi};
  }
  Box BoxOf(int a, int k) const { return Box{bin[a][k].lo, bin[a][k].hi}; }
  void Join(const Bins& o)
  {
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t rest = o.used[a]; rest; rest &= rest - 1u) {
        const int b = __builtin_ctz(rest);
        Box x;
        if (used[a] & (1u << b)) {
          x = BoxOf(a, b);
          cnt[a][b] += o.cnt[a][b];
        } else {
          cnt[a][b] = o.cnt[a][b];
        }
        x.Extend(o.BoxOf(a, b));
        bin[a][b] = {x.lo, x.hi};
      }
    for (int a = 0; a < 3; ++a) used[a] |= o.used[a];
  }
};

struct Builder {
  BigVector<PrimRef> refs;  // not zero-filled: every element is written first
  int maxLeaf = kDefaultLeaf;
  std::uint32_t sahBlock = 1;  // --bvh-sah-block
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

  // A leaf's intersection cost: its primitives in blocks of sahBlock (the
  // SIMD packs test a block at once; Embree's sahBlockSize).
  float Blocks(std::uint32_t c) const { return float((c + sahBlock - 1u) / sahBlock); }
  // Bins for a node of n references: Embree's 4 + n / 20, at most kBins.
  static int BinsFor(std::uint32_t n)
  {
    return n >= 20u * (kBins - kMinBins) ? kBins : kMinBins + static_cast<int>(n / 20u);
  }

  // The SAH sweep over m bins in order: boxOf(j) the bin's box, leftN(j)
  // the references it adds to the left side, rightN(j) those it adds to the
  // right side; take(j, cost) for each split after bin j with references on
  // both sides, left to right (cost without the parent's area).
  template <class BoxOf, class LeftN, class RightN, class Take>
  void SahSweep(int m, BoxOf boxOf, LeftN leftN, RightN rightN, Take take) const
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
      take(j, acc.Area() * Blocks(c) + rightArea[j + 1] * Blocks(rightCnt[j + 1]));
    }
  }

  // The best binned-SAH object split of refs[begin, end) over the three
  // axes (cost without the parent's area; axis -1: none), with the boxes of
  // its two sides (the spatial-split test measures their overlap).
  struct ObjectSplit {
    float cost = INFINITY;
    int axis = -1, split = -1;
    float scale = 0.0f;
    int bins = kBins;
    Box left, right;
  };
  ObjectSplit FindObjectSplit(const PrimRef* span, std::uint32_t n, const Bounds2& nb) const
  {
    const std::uint32_t begin = 0, end = n;
    const Box& cb = nb.cb;
    const F4 ext = cb.hi - cb.lo;
    // Binned SAH over all three axes, binned in one pass.
    float scale[3];
    const int nBins = BinsFor(n);
    for (int a = 0; a < 3; ++a) scale[a] = ext[a] > 0.0f ? float(nBins) / ext[a] : 0.0f;
    const F4 sc = {scale[0], scale[1], scale[2], 0.0f};
    Bins bins;
    Reduce(bins, begin, end, [&](Bins& acc, std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) {
        const PrimRef& r = span[i];
        const F4 lo = r.Lo();
        const F4 f = (0.5f * (lo + r.hi) - cb.lo) * sc;
        for (int a = 0; a < 3; ++a) {
          if (ext[a] <= 0.0f) continue;
          const int k = std::min(nBins - 1, static_cast<int>(f[a]));
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
      for (std::uint32_t rest = bins.used[a]; rest; rest &= rest - 1u) used[m++] = __builtin_ctz(rest);
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
      best.bins = nBins;
      for (std::uint32_t rest = bins.used[best.axis]; rest; rest &= rest - 1u) {
        const int b = __builtin_ctz(rest);
        (b <= best.split ? best.left : best.right).Extend(bins.BoxOf(best.axis, b));
      }
    }
    return best;
  }

  // Partitions refs[0, n) by the object split; returns the size of the
  // left side (n / 2, the order kept, when one side would be empty). The
  // loop is std::partition's (libstdc++'s bidirectional form, and so its
  // order), gathering the box and centroid box of each side on the way
  // (`sides`, when given: the children need no pass of their own; `known`
  // false when a side came out empty).
  static std::uint32_t PartitionObject(PrimRef* span, std::uint32_t n, const Box& cb, const ObjectSplit& os,
                                       Bounds2* sides = nullptr, bool* known = nullptr)
  {
    const auto isLeft = [&](const PrimRef& r) {
      const int b = std::min(os.bins - 1, static_cast<int>((r.Centroid()[os.axis] - cb.lo[os.axis]) * os.scale));
      return b <= os.split;
    };
    Bounds2 lb, rb;
    PrimRef* first = span;
    PrimRef* last = span + n;
    for (;;) {
      for (;;) {
        if (first == last) goto done;
        if (!isLeft(*first)) break;
        lb.Add(*first++);
      }
      --last;  // *first is a right one
      for (;;) {
        if (first == last) {
          rb.Add(*first);
          goto done;
        }
        if (isLeft(*last)) break;
        rb.Add(*last--);
      }
      std::iter_swap(first, last);
      lb.Add(*first++);
      rb.Add(*last);
    }
  done:
    const auto mid = static_cast<std::uint32_t>(first - span);
    const bool split = mid != 0 && mid != n;
    if (sides) sides[0] = lb, sides[1] = rb;
    if (known) *known = split;
    return split ? mid : n / 2;
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
  std::unique_ptr<BuildNode> BuildSpatial(BigVector<PrimRef> v, int depth, double budget)
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
    BigVector<PrimRef> left, right;
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
      if (!(best < INFINITY) || (n <= static_cast<std::uint32_t>(maxLeaf) && Blocks(n) <= splitCost)) {
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
    BigVector<PrimRef>().swap(v);
    if (n > kParallelThreshold) {
      tbb::parallel_invoke([&] { node->kids[0] = BuildSpatial(std::move(left), depth + 1, shareL); },
                           [&] { node->kids[1] = BuildSpatial(std::move(right), depth + 1, shareR); });
    } else {
      node->kids[0] = BuildSpatial(std::move(left), depth + 1, shareL);
      node->kids[1] = BuildSpatial(std::move(right), depth + 1, shareR);
    }
    return node;
  }

  // How refs[begin, end) is cut: its box, and either a leaf (its refs
  // sorted by id, so each type is one run) or the partition at `mid`.
  // `sides`: the children's boxes and centroid boxes, when the partition
  // found them (`known`).
  struct Step {
    Box box;
    bool leaf = false;
    std::uint32_t mid = 0;
    Bounds2 sides[2];
    bool known = false;
  };
  // `given`: the node's box and centroid box, when its parent's partition
  // gathered them.
  Step Decide(std::uint32_t begin, std::uint32_t end, int depth, const Bounds2* given)
  {
    Step step;
    const std::uint32_t n = end - begin;
    const Bounds2 nb = given ? *given : NodeBounds(refs.data() + begin, n);
    step.box = nb.box;
    const Box& cb = nb.cb;
    auto leaf = [&]() {
      std::sort(refs.begin() + begin, refs.begin() + end,
                [](const PrimRef& x, const PrimRef& y) { return x.Id() < y.Id(); });
      step.leaf = true;
      return step;
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
    } else if (n <= static_cast<std::uint32_t>(maxLeaf) && n <= sahBlock &&
               step.box.Area() <= std::numeric_limits<float>::max()) {
      // One block: the leaf costs 1 and any split 1 + a cost >= 0 (finite
      // areas), so the SAH below would take the leaf (the same tree; with
      // sah_block 4 every leaf skips its binning).
      return leaf();
    } else {
      const ObjectSplit os = FindObjectSplit(refs.data() + begin, n, nb);
      const float parentArea = step.box.Area();
      const float leafCost = Blocks(n);
      const float splitCost = parentArea > 0.0f ? 1.0f + os.cost / parentArea : INFINITY;
      if (os.axis < 0 || (n <= static_cast<std::uint32_t>(maxLeaf) && leafCost <= splitCost)) {
        if (n <= static_cast<std::uint32_t>(maxLeaf)) return leaf();
        mid = begin + n / 2;
        std::nth_element(refs.begin() + begin, refs.begin() + mid, refs.begin() + end, byCentroid(axis));
      } else {
        mid = begin + PartitionObject(refs.data() + begin, n, cb, os, step.sides, &step.known);
      }
    }
    step.mid = mid;
    return step;
  }

  // The top of the tree (subtrees of more than kParallelThreshold refs) as
  // BuildNodes, built in parallel; each smaller subtree straight into a flat
  // array of its own (BuildFlat), in the final layout, which Flatten copies
  // into place. At 10^7 references a BuildNode per node was 10^7 mallocs,
  // and their pages, freed again.
  std::unique_ptr<BuildNode> Build(std::uint32_t begin, std::uint32_t end, int depth, const Bounds2* given)
  {
    auto node = std::make_unique<BuildNode>();
    if (end - begin <= kParallelThreshold) {
      node->sub.resize(1);
      std::uint64_t made = 0;
      BuildFlat(begin, end, depth, given, node->sub, 0, made);
      nodeCount += made;
      return node;
    }
    ++nodeCount;
    const Step s = Decide(begin, end, depth, given);
    node->box = s.box;
    if (s.leaf) {
      node->first = begin;
      node->count = end - begin;
      return node;
    }
    tbb::parallel_invoke([&] { node->kids[0] = Build(begin, s.mid, depth + 1, s.known ? &s.sides[0] : nullptr); },
                         [&] { node->kids[1] = Build(s.mid, end, depth + 1, s.known ? &s.sides[1] : nullptr); });
    return node;
  }

  // Subtree refs[begin, end) into out[self] and slots appended to `out`,
  // as Flatten lays nodes out: a node's two children in adjacent new slots,
  // then the first child's subtree, then the second's.
  void BuildFlat(std::uint32_t begin, std::uint32_t end, int depth, const Bounds2* given, std::vector<BVHNode>& out,
                 std::uint32_t self, std::uint64_t& made)
  {
    ++made;
    const Step s = Decide(begin, end, depth, given);
    if (s.leaf) {
      StoreNode(s.box, begin, end - begin, out[self]);
      return;
    }
    const auto first = static_cast<std::uint32_t>(out.size());
    StoreNode(s.box, first, 0, out[self]);
    out.resize(out.size() + 2);
    BuildFlat(begin, s.mid, depth + 1, s.known ? &s.sides[0] : nullptr, out, first, made);
    BuildFlat(s.mid, end, depth + 1, s.known ? &s.sides[1] : nullptr, out, first + 1, made);
  }
};

// A subtree built flat, and where Flatten puts it: its root at `self`, its
// descendants from `base`.
struct FlatCopy {
  BuildNode* node;
  std::uint32_t self, base;
};

// Depth-first flattening: children of node i go to two adjacent new slots.
// `refs`: where the leaves of a spatial-split build put their ids (else
// null: the leaves already name their range of the builder's references).
// Subtrees built flat get their slots here and are listed in `copies`.

void Flatten(BuildNode& b, std::uint32_t self, BigVector<BVHNode>& nodes, AccelInfo& info,
             BigVector<std::uint32_t>* refs, std::vector<FlatCopy>& copies)
{
  if (!b.sub.empty()) {
    // Its slots now; its nodes copied afterwards, in parallel (CopyFlat).
    const auto base = static_cast<std::uint32_t>(nodes.size());
    copies.push_back({&b, self, base});
    nodes.resize(base + b.sub.size() - 1);
    return;
  }
  StoreNode(b.box, b.first, b.count, nodes[self]);
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
  Flatten(*b.kids[0], first, nodes, info, refs, copies);
  Flatten(*b.kids[1], first + 1, nodes, info, refs, copies);
}

// The subtrees built flat into their slots, their children's indices moved
// with them.
void CopyFlat(const std::vector<FlatCopy>& copies, BigVector<BVHNode>& nodes, AccelInfo& info)
{
  std::atomic<std::uint64_t> leaves{0};
  tbb::parallel_for(std::size_t(0), copies.size(), [&](std::size_t c) {
    const FlatCopy& fc = copies[c];
    std::vector<BVHNode>& sub = fc.node->sub;
    std::uint64_t nLeaves = 0;
    const auto shift = [&](BVHNode x) {
      if (x.count > 0)
        ++nLeaves;
      else
        x.first += fc.base - 1u;
      return x;
    };
    nodes[fc.self] = shift(sub[0]);
    for (std::size_t i = 1; i < sub.size(); ++i) nodes[fc.base + i - 1] = shift(sub[i]);
    std::vector<BVHNode>().swap(sub);
    leaves += nLeaves;
  });
  info.leaves += leaves.load();
}

}  // namespace

// The build's parameters as `structure.params` reports them.
static std::string BuildParams(int maxLeaf, std::uint32_t block)
{
  return fmt::format("leaf={} bins={}..{}{}", maxLeaf, kMinBins, kBins,
                     block > 1 ? fmt::format(" sah_block={}", block) : "");
}

BVHData BuildBVH(const Scene& scene, const AccelParams& params, AccelInfo& info)
{
  if (params.bvhLeaf < 0 || params.bvhLeaf > 255)
    throw InputError(fmt::format("--bvh-leaf {} is not in 1..255", params.bvhLeaf));
  if (params.bvhSahBlock < 0 || params.bvhSahBlock > 64)
    throw InputError(fmt::format("--bvh-sah-block {} is not in 1..64", params.bvhSahBlock));
  const std::string& quality = params.bvhQuality;
  if (!quality.empty() && quality != "medium" && quality != "high")
    throw InputError(fmt::format("--bvh-quality '{}': expected medium or high", quality));
  const bool spatial = quality == "high";
  Builder bld;
  bld.maxLeaf = params.bvhLeaf > 0 ? params.bvhLeaf : kDefaultLeaf;
  bld.sahBlock = params.bvhSahBlock > 0 ? std::uint32_t(params.bvhSahBlock) : 1u;
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
    info.params = BuildParams(bld.maxLeaf, bld.sahBlock);
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
    root = bld.Build(0, n, 0, nullptr);
  }
  std::vector<FlatCopy> copies;
  out.nodes.reserve(bld.nodeCount.load());
  out.nodes.resize(1);
  if (spatial) {
    out.refs.reserve(n + bld.splitRefs.load());
    Flatten(*root, 0, out.nodes, info, &out.refs, copies);
  } else {
    Flatten(*root, 0, out.nodes, info, nullptr, copies);
    out.refs.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, 1u << 14),
                      [&](const tbb::blocked_range<std::uint32_t>& r) {
                        for (std::uint32_t i = r.begin(); i < r.end(); ++i) out.refs[i] = bld.refs[i].Id();
                      });
  }
  CopyFlat(copies, out.nodes, info);
  out.header.nNodes = static_cast<std::uint32_t>(out.nodes.size());
  out.header.nRefs = static_cast<std::uint32_t>(out.refs.size());
  info.nodes = out.nodes.size();
  info.refs = out.refs.size();
  info.emptyLeaves = 0;
  info.bytes = out.nodes.size() * sizeof(BVHNode) + out.refs.size() * sizeof(std::uint32_t);
  info.params = BuildParams(bld.maxLeaf, bld.sahBlock);
  if (spatial)
    info.params += fmt::format(" quality=high spatial_bins={} split_refs={}", kSpatialBins, bld.splitRefs.load());
  return out;
}

void AddBVHParents(BVHData& bvh, AccelInfo& info)
{
  if (bvh.header.parents != 0 || bvh.nodes.empty()) return;
  const std::size_t at = bvh.refs.size();
  if (at + bvh.nodes.size() > std::numeric_limits<std::uint32_t>::max())
    throw RuntimeError(fmt::format("BVH of {} nodes and {} references: parent links past 2^32 entries",
                                   bvh.nodes.size(), at));
  bvh.refs.resize(at + bvh.nodes.size());
  bvh.refs[at] = 0;
  for (std::size_t i = 0; i < bvh.nodes.size(); ++i) {
    const BVHNode& n = bvh.nodes[i];
    if (n.count == 0) bvh.refs[at + n.first] = bvh.refs[at + n.first + 1] = static_cast<std::uint32_t>(i);
  }
  bvh.header.parents = static_cast<std::uint32_t>(at);
  info.bytes += bvh.nodes.size() * sizeof(std::uint32_t);
}

}  // namespace cr
