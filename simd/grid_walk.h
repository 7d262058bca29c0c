// The pieces of the uniform grid's 3D-DDA (kernels/grid.h Grid_Trace) that
// the packet and single-ray paths share: the cell planes, the entry with the
// first-cell correction on N lanes at once, and the walk of one ray from a
// given cell with the cell's primitives tested 4 at a time.
#pragma once

#include "simd/bvh_packet.h"
#include "simd/bvh_single.h"
#include "simd/kernel_common.h"
#include "simd/prim_range.h"

namespace cr::simd::CR_SIMD_NS {

// Grid_Plane of kernels/grid.h: bmin + (float)i * cellSize, in float.
CR_SIMD_INLINE float GridPlane(const GridHeader& g, int axis, int i)
{
  return g.bmin[axis] + static_cast<float>(i) * g.cellSize[axis];
}
template <int N>
CR_SIMD_INLINE vfloat<N> GridPlaneN(const GridHeader& g, int axis, vint<N> i)
{
  return vfloat<N>(g.bmin[axis]) + ToFloat(i) * vfloat<N>(g.cellSize[axis]);
}

// Grid_EnterAt on axis a for the lanes of `in` at once, each lane in a grid
// of its own (planes bmin + i * cs, res cells; GridPlane's operations): the
// cell each lane is in at its tEnter, corrected to the walk's plane
// parameters; org, dir, inv, invNeg the lanes' ray on that axis.
template <int N>
CR_SIMD_INLINE vint<N> GridPacket_CellAt(vfloat<N> bmin, vfloat<N> cs, vint<N> resV, vfloat<N> org, vfloat<N> dir,
                                         vfloat<N> inv, vbool<N> invNeg, vfloat<N> tEnter, vbool<N> in)
{
  const vint<N> one(1), zero(0);
  const vint<N> top = resV - one;
  const vfloat<N> p = org + tEnter * dir;
  vfloat<N> rel = (p - (bmin + ToFloat(zero) * cs)) / cs;
  rel = FMin(FMax(rel, vfloat<N>(0.0f)), ToFloat(top));
  vint<N> c = FloorToInt(rel);
  auto planeT = [&](vint<N> i) { return PlaneTN<N>(bmin + ToFloat(i) * cs, org, inv); };
  const vbool<N> up = AndNot(in, invNeg), down = in & invNeg;
  // Each loop is a scalar `while` run on its lanes at once: a lane leaves
  // it at its first failed test. Lanes stepping up run
  //   while (c > 0 && T(c) > tEnter) --c;  while (c < res - 1 && T(c + 1) < tEnter) ++c;
  // lanes stepping down
  //   while (c < res - 1 && T(c + 1) > tEnter) ++c;  while (c > 0 && T(c) < tEnter) --c;
  // (the second loop below serves the second of the first and the first of the second).
  vbool<N> m = up & (c > zero);
  while (Any(m = m & (planeT(c) > tEnter))) {
    c = c - Select(m, one, zero);
    m = m & (c > zero);
  }
  m = (up | down) & (c < top);
  for (;;) {
    const vfloat<N> tn = planeT(c + one);
    m = m & ((down & (tn > tEnter)) | AndNot(tn < tEnter, down));
    if (None(m)) break;
    c = c + Select(m, one, zero);
    m = m & (c < top);
  }
  m = down & (c > zero);
  while (Any(m = m & (planeT(c) < tEnter))) {
    c = c - Select(m, one, zero);
    m = m & (c > zero);
  }
  return c;
}

// The lanes of `active` that enter the grid, and each one's first cell
// (kernels/grid.h Grid_Trace before its loop).
template <int N, bool kFast>
CR_SIMD_INLINE vbool<N> GridPacket_Enter(const GridHeader& g, const RayPacket<N>& P, const HitPacket<N>& H,
                                         vbool<N> active, vint<N> cell[3], vfloat<N>* tEnterOut = nullptr)
{
  vfloat<N> tEnter;
  const vbool<N> in =
      active & Box_IntersectRays<kFast, N>(g.bmin, g.bmax, P.org, P.inv, P.invNeg, P.tmin, H.t, tEnter);
  if (tEnterOut) *tEnterOut = tEnter;
  if (None(in)) return in;
  for (int a = 0; a < 3; ++a)
    cell[a] = GridPacket_CellAt<N>(vfloat<N>(g.bmin[a]), vfloat<N>(g.cellSize[a]), vint<N>(static_cast<int>(g.res[a])),
                                   P.org[a], P.dir[a], P.inv[a], P.invNeg[a], tEnter, in);
  return in;
}

// Grid_EnterAt of kernels/grid.h for one ray: the cell of grid g the ray is
// in at parameter tEnter, corrected to the plane parameters of the walk.
CR_SIMD_INLINE void GridSingle_EnterAt(const GridHeader& g, const Ray& ray, float tEnter, int cell[3])
{
  for (int a = 0; a < 3; ++a) {
    const int res = static_cast<int>(g.res[a]);
    const float p = ray.org[a] + tEnter * ray.dir[a];
    float rel = (p - GridPlane(g, a, 0)) / g.cellSize[a];
    // fmax(rel, 0) then fmin(., res - 1) as selects (NaN -> 0, as fmax).
    rel = rel > 0.0f ? rel : 0.0f;
    rel = rel < static_cast<float>(res - 1) ? rel : static_cast<float>(res - 1);
    int c = static_cast<int>(__builtin_floorf(rel));
    auto planeT = [&](int i) { return PlaneT(GridPlane(g, a, i), ray.org[a], ray.inv[a]); };
    if (!(ray.inv[a] < 0.0f)) {
      while (c > 0 && planeT(c) > tEnter) --c;
      while (c < res - 1 && planeT(c + 1) < tEnter) ++c;
    } else {
      while (c < res - 1 && planeT(c + 1) > tEnter) ++c;
      while (c > 0 && planeT(c) < tEnter) --c;
    }
    cell[a] = c;
  }
}

// The walk of one ray through grid g (cell offsets cellStart, references
// refs) from cell `first` (not yet tested) on; `pr` the ray prepared for
// the 4-wide primitive tests (PackRay_Init, anyHit set; a moving scene's a
// TimedPackRay with its time, simd/motion.h); `hit` from Hit_Init
// or the hit so far; true when an any-hit query is answered. The walk keeps the
// crossing parameter of each axis's next plane and recomputes only the axis
// it stepped: the other two planes have not changed, so their parameters
// are the scalar loop's recomputed values, bit for bit.
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE bool GridSingle_Walk(const KernelScene& sc, const GridHeader& g, const std::uint32_t* cellStart,
                                    const std::uint32_t* refs, const PackRay<4>& pr, const Ray& ray, Hit& hit,
                                    const int first[3], int anyHit, TraceStatsSum& st)
{
  // Per axis: cell coordinate, step, exit plane crossing, and the change of
  // the cell index per step (strides 1, res x, res x res y).
  int cell[3], step[3], res[3], dIdx[3];
  float tNext[3];
  const int stride[3] = {1, int(g.res[0]), int(g.res[0] * g.res[1])};
  for (int a = 0; a < 3; ++a) {
    cell[a] = first[a];
    res[a] = static_cast<int>(g.res[a]);
    step[a] = ray.inv[a] < 0.0f ? -1 : 1;
    dIdx[a] = step[a] * stride[a];
    tNext[a] = PlaneT(GridPlane(g, a, step[a] > 0 ? cell[a] + 1 : cell[a]), ray.org[a], ray.inv[a]);
  }
  std::uint32_t idx = std::uint32_t(cell[0] + stride[1] * cell[1] + stride[2] * cell[2]);
  for (;;) {
    if constexpr (kStats) {
      ++st.nTS;
      ++st.nLeaves;
    }
    const std::uint32_t begin = cellStart[idx], end = cellStart[idx + 1];
    if (begin == end) {
      if constexpr (kStats) ++st.nEmptyLeaves;
    } else if (RayRefs_Intersect<kTypes, kFast, kStats>(sc, refs, begin, end, pr, hit, anyHit, st) && anyHit) {
      return true;
    }
    // Exit face: the smallest crossing, x before y before z on ties (the
    // scalar loop's strict <; no crossing is NaN), chosen without branches,
    // which incoherent rays would mispredict.
    const float t01 = tNext[1] < tNext[0] ? tNext[1] : tNext[0];
    const int axis = tNext[2] < t01 ? 2 : (tNext[1] < tNext[0] ? 1 : 0);
    if (hit.t <= tNext[axis]) return false;
    cell[axis] += step[axis];
    if (static_cast<unsigned>(cell[axis]) >= static_cast<unsigned>(res[axis])) return false;
    idx += static_cast<std::uint32_t>(dIdx[axis]);
    tNext[axis] =
        PlaneT(GridPlane(g, axis, step[axis] > 0 ? cell[axis] + 1 : cell[axis]), ray.org[axis], ray.inv[axis]);
  }
}

}  // namespace cr::simd::CR_SIMD_NS
