/* The OpenCL program: kernel entry points over the portable traversals. The
 * host (host/cl/cl_options.cpp) compiles it with options derived from the
 * scene and the query, so that only what they need is modelled:
 *   CR_FP64 | CR_FAST                 precision (intersect.h); default robust
 *   CR_HAS_<TYPE> = 0|1               primitive types present (default 1;
 *                                     kernels/types.h CR_PRIM_TYPES, CR_IF)
 *   CR_HAS_MOTION = 0|1               moving pieces and ray times (default
 *                                     1; kernels/motion.h)
 *   CR_ACCEL_ONE, CR_ACCEL_<UPPER>   the one traversal compiled (its name
 *                                     in kernels/types.h CR_ACCEL_TYPES);
 *                                     none: all, chosen by the `accel`
 *                                     argument (CR_ACCEL_ID_*)
 *   CR_ANYHIT = 0|1                   occlusion query; absent: argument
 *   CR_UNIFIED = 0|1                  unified hit records; absent: argument
 *   CR_STATS                          per-ray counters written to `stats`
 *   CR_VARIANT_RAY, CR_VARIANT_PACKET the kernels compiled (absent: both)
 *   CR_SOURCE_RAYS, CR_SOURCE_CAMERA  rays from a buffer or generated here
 *                                     (absent: both)
 *   CR_PACKET_W, CR_PACKET_H          work-group tile of the packet kernels
 *   CR_COLD_INLINE                    cold paths inlined (prelude.h;
 *                                     CELLRAY_CL_COLD=inline)
 *   CR_CAMERA_FP64                    primary rays generated in double, as
 *                                     host/scene/camera.cpp does (bit-equal)
 *   CR_MATERIALS, CR_LIGHTS           reserved for the renderer's kernels
 *   CR_INJECT_BUILD_FAULT             an #error (the injected build failure
 *                                     of host/cl/cl_fault.h)
 * Every kernel takes the same scene and structure arguments (CR_SCENE_PARAMS)
 * so that the host binds them once per program. */
#include "prelude.h"

#ifdef CR_INJECT_BUILD_FAULT
/* host/cl/cl_fault.h: CELLRAY_CL_FAULT=build makes the compiler fail here. */
#error "build failure injected by CELLRAY_CL_FAULT=build"
#endif

#ifdef CR_CAMERA_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double camreal;
typedef double4 camreal4;
#else
typedef float camreal;
typedef float4 camreal4;
#endif

#ifndef CR_PACKET_W
#define CR_PACKET_W 8
#endif
#ifndef CR_PACKET_H
#define CR_PACKET_H 8
#endif
#define CR_PACKET_SIZE (CR_PACKET_W * CR_PACKET_H)

#include "accels.h"

/* Whether structure U is the one traced: in a build for one structure
 * (CR_ACCEL_ONE) the one compiled, else the `accel` argument's. CR_IF_WITH
 * keeps a structure's code only where the build compiles it. */
#ifdef CR_ACCEL_ONE
#define CR_ACCEL_TAKEN(U) 1
#else
#define CR_ACCEL_TAKEN(U) (accel == CR_ACCEL_ID_##U)
#endif
#define CR_IF_WITH(U, code) CR_CAT(CR_IF_, CR_WITH_##U)(code)

/* The scene and structure arguments of every kernel, in binding order
 * (host/cl/cl_tracer.cpp binds them by these positions): for each primitive
 * type of CR_PRIM_TYPES its array and its count (arguments 2k and 2k + 1),
 * the primitive ids, the pieces' motion (kernels/motion.h; a placeholder
 * for a static scene), for each structure of CR_ACCEL_TYPES its header,
 * nodes and references (3 arguments each), then accel, anyHitArg,
 * unifiedArg. */
#define CR_PRIM_PARAM_(T, U, a) CR_GLOBAL const T *a, uint a##Count,
#define CR_PRIM_ARG_(T, U, a) a, a##Count,
#define CR_ACCEL_PARAM_(N, U, l, H, Nd) CR_GLOBAL const H *l##Header, CR_GLOBAL const Nd *l##Nodes, CR_GLOBAL const uint *l##Refs,
#define CR_ACCEL_ARG_(N, U, l, H, Nd) l##Header, l##Nodes, l##Refs,
#define CR_SCENE_PARAMS                                                                                         \
  CR_PRIM_TYPES(CR_PRIM_PARAM_)                                                                                \
  CR_GLOBAL const uint *primIds, CR_GLOBAL const float *motion, CR_ACCEL_TYPES(CR_ACCEL_PARAM_) int accel,           \
      int anyHitArg, int unifiedArg
#ifdef CR_ANYHIT
#define CR_QUERY_ANYHIT CR_ANYHIT
#else
#define CR_QUERY_ANYHIT anyHitArg
#endif
#ifdef CR_UNIFIED
#define CR_QUERY_UNIFIED CR_UNIFIED
#else
#define CR_QUERY_UNIFIED unifiedArg
#endif

/* The arrays and their ranges of unified indices, and the motion, from the
 * arguments (Trace_PrimView(CR_PRIM_TYPES(CR_PRIM_ARG_) motion)). */
#define CR_PRIM_VIEW_SET_(T, U, a) \
  pv.a = a;                        \
  pv.ranges.begin[CR_PRIM_##U] = n; \
  n += a##Count;
CR_FUNC PrimView Trace_PrimView(CR_PRIM_TYPES(CR_PRIM_PARAM_) CR_GLOBAL const float* motion)
{
  PrimView pv;
  uint n = 0u;
#if CR_HAS_MOTION
  pv.motion = motion;
#else
  pv.motion = 0;
  (void)motion;
#endif
  CR_PRIM_TYPES(CR_PRIM_VIEW_SET_)
  for (uint k = CR_NUM_PRIM_TYPES; k < CR_PRIM_RANGE_SLOTS; ++k) pv.ranges.begin[k] = n; /* the end, and padding */
  return pv;
}

/* Primary ray through pixel (px, py) of a width x height image, with the
 * formula and operation order of host/scene/camera.cpp PrimaryRay (in double
 * under CR_CAMERA_FP64, so that both produce the same float ray). */
CR_FUNC RayRecord Camera_Ray(float4 org, camreal4 fwd, camreal4 right, camreal4 up, camreal tanHalf, float tmin,
                             int px, int py, int width, int height)
{
  const camreal span = height > 1 ? (camreal)(height - 1) : (camreal)1;
  const camreal x = ((camreal)2 * (camreal)px - (camreal)(width - 1)) / span * tanHalf;
  const camreal y = ((camreal)(height - 1) - (camreal)2 * (camreal)py) / span * tanHalf;
  RayRecord r;
  r.org[0] = org.x;
  r.org[1] = org.y;
  r.org[2] = org.z;
  r.dir[0] = (float)(fwd.x + x * right.x + y * up.x);
  r.dir[1] = (float)(fwd.y + x * right.y + y * up.y);
  r.dir[2] = (float)(fwd.z + x * right.z + y * up.z);
  r.tmin = tmin;
  r.tmax = CR_INF;
  return r;
}

/* Field by field: a struct copy becomes a memcpy call, which the work-item
 * loop vectoriser cannot widen. */
CR_FUNC RayRecord Trace_LoadRay(CR_GLOBAL const RayRecord* rays, uint i)
{
  CR_GLOBAL const RayRecord* p = rays + i;
  RayRecord r;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    r.org[a] = p->org[a];
    r.dir[a] = p->dir[a];
  }
  r.tmin = p->tmin;
  r.tmax = p->tmax;
  return r;
}

CR_FUNC void Trace_StoreHit(CR_GLOBAL HitRecord* hits, uint i, HitRecord h)
{
  CR_GLOBAL HitRecord* p = hits + i;
  p->t = h.t;
  p->prim = h.prim;
  p->u = h.u;
  p->v = h.v;
}

CR_FUNC void Trace_StoreStats(CR_GLOBAL TraceStats* stats, uint i, const TraceStats* st)
{
#ifdef CR_STATS
  CR_GLOBAL TraceStats* p = stats + i;
  p->nIT = st->nIT;
  p->nTS = st->nTS;
  p->nLeaves = st->nLeaves;
  p->nEmptyLeaves = st->nEmptyLeaves;
#endif
}

/* The time of ray i: times[i] where the rays have times (hasTimes), else 0. */
CR_FUNC float Trace_Time(CR_GLOBAL const float* times, int hasTimes, uint i)
{
#if CR_HAS_MOTION
  return hasTimes ? times[i] : 0.0f;
#else
  (void)times;
  (void)hasTimes;
  (void)i;
  return 0.0f;
#endif
}

/* The structure arguments of Trace_One and Trace_Packet, by name. */
#define CR_TRACE_ONE_PARAMS CR_ACCEL_TYPES(CR_ACCEL_PARAM_) int accel
#define CR_TRACE_ONE_ARGS CR_ACCEL_TYPES(CR_ACCEL_ARG_) accel

#if !defined(CR_VARIANT_PACKET)

/* Ray record i through the structure the build (or `accel`) selects; its
 * answer to hits[i], its counters to stats (when counted). anyHitArg and
 * unifiedArg are read only by a generic build (CR_QUERY_*). */
CR_FUNC void Trace_One(const PrimView* pv, CR_TRACE_ONE_PARAMS, CR_GLOBAL const uint* primIds, int anyHitArg,
                       int unifiedArg, const RayRecord* rec, float time, uint i, CR_GLOBAL HitRecord* hits,
                       CR_GLOBAL TraceStats* stats)
{
  Ray ray;
  Ray_Init(&ray, rec);
  ray.anyHit = CR_QUERY_ANYHIT;
  ray.time = (real)time;
  Hit hit;
  Hit_Init(&hit, &ray);
  TraceStats st = {0, 0, 0, 0};
#define CR_TRACE_ONE_(N, U, l, H, Nd)                                                                     \
  CR_IF_WITH(U, if (CR_ACCEL_TAKEN(U)) N##_Trace(l##Header, l##Nodes, l##Refs, pv, &ray, &hit, CR_QUERY_ANYHIT, &st);)
  CR_ACCEL_TYPES(CR_TRACE_ONE_)
#undef CR_TRACE_ONE_
  Trace_StoreHit(hits, i, Hit_ToRecord(&hit, pv, primIds, CR_QUERY_ANYHIT, CR_QUERY_UNIFIED));
  Trace_StoreStats(stats, i, &st);
}

/* Per-ray variant: each work-item traverses alone. hits[i] answers rays[i]
 * (at times[i] where hasTimes). The BVH's wide packet walk (CR_BVH_WIDE_PACKET,
 * kernels/bvh_wide.cl): each work-item traces rays [8 i, 8 i + 8) together. */
#if !defined(CR_SOURCE_CAMERA) && defined(CR_BVH_WIDE_PACKET) && !defined(CR_FP64)
__kernel void Trace_Rays(CR_SCENE_PARAMS, CR_GLOBAL const RayRecord* rays, uint nRays, CR_GLOBAL HitRecord* hits,
                         CR_GLOBAL TraceStats* stats, CR_GLOBAL const float* times, int hasTimes)
{
  const uint first = (uint)get_global_id(0) * 8u;
  if (first >= nRays) return;
  const int n = nRays - first < 8u ? (int)(nRays - first) : 8;
  const PrimView pv = Trace_PrimView(CR_PRIM_TYPES(CR_PRIM_ARG_) motion);
  Ray ray[8];
  Hit hit[8];
  TraceStats st[8];
  for (int l = 0; l < 8; ++l) {
    /* Lanes past the last ray repeat the first (inactive). */
    const uint i = first + (uint)(l < n ? l : 0);
    const RayRecord rec = Trace_LoadRay(rays, i);
    Ray_Init(&ray[l], &rec);
    ray[l].anyHit = CR_QUERY_ANYHIT;
    ray[l].time = (real)Trace_Time(times, hasTimes, i);
    Hit_Init(&hit[l], &ray[l]);
    st[l].nIT = st[l].nTS = st[l].nLeaves = st[l].nEmptyLeaves = 0;
  }
  BVH_TracePacket8(bvhNodes, bvhRefs, &pv, ray, hit, n, CR_QUERY_ANYHIT, st);
  (void)bvhHeader;
  (void)accel;
  for (int l = 0; l < n; ++l) {
    Trace_StoreHit(hits, first + (uint)l, Hit_ToRecord(&hit[l], &pv, primIds, CR_QUERY_ANYHIT, CR_QUERY_UNIFIED));
    Trace_StoreStats(stats, first + (uint)l, &st[l]);
  }
}
#elif !defined(CR_SOURCE_CAMERA)
__kernel void Trace_Rays(CR_SCENE_PARAMS, CR_GLOBAL const RayRecord* rays, uint nRays, CR_GLOBAL HitRecord* hits,
                         CR_GLOBAL TraceStats* stats, CR_GLOBAL const float* times, int hasTimes)
{
  const uint i = (uint)get_global_id(0);
  if (i >= nRays) return;
  const PrimView pv = Trace_PrimView(CR_PRIM_TYPES(CR_PRIM_ARG_) motion);
  const RayRecord rec = Trace_LoadRay(rays, i);
  Trace_One(&pv, CR_TRACE_ONE_ARGS, primIds, anyHitArg, unifiedArg, &rec, Trace_Time(times, hasTimes, i), i, hits,
            stats);
}

#endif

#ifndef CR_SOURCE_RAYS
/* Per-ray variant of the camera's primary rays, generated here; the 2D range
 * covers the image in tiles; hits are row-major. */
__kernel void Trace_Primary(CR_SCENE_PARAMS, float4 org, camreal4 fwd, camreal4 right, camreal4 up, camreal tanHalf,
                            float tmin, int width, int height, CR_GLOBAL HitRecord* hits,
                            CR_GLOBAL TraceStats* stats)
{
  const int px = (int)get_global_id(0), py = (int)get_global_id(1);
  if (px >= width || py >= height) return;
  const uint i = (uint)py * (uint)width + (uint)px;
  const PrimView pv = Trace_PrimView(CR_PRIM_TYPES(CR_PRIM_ARG_) motion);
  const RayRecord rec = Camera_Ray(org, fwd, right, up, tanHalf, tmin, px, py, width, height);
  Trace_One(&pv, CR_TRACE_ONE_ARGS, primIds, anyHitArg, unifiedArg, &rec, 0.0f, i, hits, stats);
}

#endif
#endif /* !CR_VARIANT_PACKET */

#if !defined(CR_VARIANT_RAY)

/* The local memory of a packet traversal: the lanes' rays and hits
 * (packet.cl), one word per lane, the group's state words, and what the
 * compiled structures' traversals need, each piece X(type, name, count).
 * The pieces are carved from one __local kernel argument, the pool
 * (CR_PACKET_LOCALS), of CR_PACKET_POOL_BYTES, which the host reads from
 * Trace_PacketPoolBytes: declared at kernel scope instead, PoCL 3.1's
 * work-group compiler (its automatic-locals pass, then LLVM 15's
 * InstCombine) crashed inside clBuildProgram on the largest programs (the
 * robust ray-margin octree's packet kernels with every primitive type;
 * docs/OPENCL.md). Each piece starts on 8 bytes (real is double under
 * CR_FP64). */
#define CR_PACKET_STATE_WORDS 12
#define CR_PACKET_LOCALS_COMMON(X)                                                                           \
  X(real, sRay, CR_PACKET_RAY_FIELDS * CR_PACKET_SIZE) X(real, sHit, CR_PACKET_HIT_FIELDS * CR_PACKET_SIZE) \
  X(uint, sLane, CR_PACKET_SIZE) X(uint, sState, CR_PACKET_STATE_WORDS)                                     \
  X(uint, sAxes, CR_PACKET_AXES_FIELDS * CR_PACKET_SIZE) X(uint, sHitG, CR_PACKET_SIZE)
#define CR_POOL_PIECE_BYTES_(T, count) (((uint)sizeof(T) * (uint)(count) + 7u) & ~7u)
#define CR_POOL_BYTES_(T, name, count) +CR_POOL_PIECE_BYTES_(T, count)
#define CR_POOL_CARVE_(T, name, count)             \
  __local T* name = (__local T*)(poolBytes + poolAt); \
  poolAt += CR_POOL_PIECE_BYTES_(T, count);
#define CR_PACKET_POOL_BYTES_(N, U, l, H, Nd) CR_CAT(CR_IF_, CR_WITH_##U)(CR_PACKET_LOCALS_##U(CR_POOL_BYTES_))
#define CR_PACKET_POOL_CARVE_(N, U, l, H, Nd) CR_CAT(CR_IF_, CR_WITH_##U)(CR_PACKET_LOCALS_##U(CR_POOL_CARVE_))
#define CR_PACKET_POOL_BYTES \
  (0u CR_PACKET_LOCALS_COMMON(CR_POOL_BYTES_) CR_ACCEL_TYPES(CR_PACKET_POOL_BYTES_))
#define CR_POOL_PARAM_(T, name, count) , __local T* name
#define CR_POOL_ARG_(T, name, count) , name
#define CR_PACKET_PARAMS_(N, U, l, H, Nd) CR_CAT(CR_IF_, CR_WITH_##U)(CR_PACKET_LOCALS_##U(CR_POOL_PARAM_))
#define CR_PACKET_ARGS_(N, U, l, H, Nd) CR_CAT(CR_IF_, CR_WITH_##U)(CR_PACKET_LOCALS_##U(CR_POOL_ARG_))
#define CR_PACKET_LOCALS                                   \
  __local uchar* poolBytes = (__local uchar*)packetPool; \
  uint poolAt = 0u;                                      \
  CR_PACKET_LOCALS_COMMON(CR_POOL_CARVE_)                \
  CR_ACCEL_TYPES(CR_PACKET_POOL_CARVE_)
/* The parameters that pass the pieces on, and the arguments: each begins
 * with its comma. */
#define CR_PACKET_PARAMS CR_PACKET_LOCALS_COMMON(CR_POOL_PARAM_) CR_ACCEL_TYPES(CR_PACKET_PARAMS_)
#define CR_PACKET_ARGS CR_PACKET_LOCALS_COMMON(CR_POOL_ARG_) CR_ACCEL_TYPES(CR_PACKET_ARGS_)

/* The hit of one lane's ray after the group's packet traversal of the
 * structure the build (or `accel`, the same for the whole group) selects. */
CR_FUNC Hit Trace_Packet(const PrimView* pv, CR_TRACE_ONE_PARAMS, const RayRecord* rec, float time, int live, uint lid,
                         int anyHit, TraceStats* st CR_PACKET_PARAMS)
{
  Ray ray;
  Ray_Init(&ray, rec);
  ray.time = (real)time;
  Hit hit;
  Hit_Init(&hit, &ray);
  Packet_StoreRay(sRay, sAxes, lid, CR_PACKET_SIZE, &ray);
  Packet_StoreHit(sHit, sHitG, lid, CR_PACKET_SIZE, &hit);
#define CR_TRACE_PACKET_(N, U, l, H, Nd) \
  CR_IF_WITH(U, if (CR_ACCEL_TAKEN(U)) CR_PACKET_CALL_##U(l##Header, l##Nodes, l##Refs);)
  CR_ACCEL_TYPES(CR_TRACE_PACKET_)
#undef CR_TRACE_PACKET_
  Packet_LoadHit(sHit, sHitG, lid, CR_PACKET_SIZE, &hit);
  return hit;
}

#ifndef CR_SOURCE_CAMERA
/* Packet variant: the work-group is a packet (consecutive rays) that walks the
 * structure together (its kernels/<lower>_packet.cl).
 * Lanes past nRays take part without a ray. */
__kernel __attribute__((reqd_work_group_size(CR_PACKET_SIZE, 1, 1))) void Trace_RaysPacket(
    CR_SCENE_PARAMS, CR_GLOBAL const RayRecord* rays, uint nRays, CR_GLOBAL HitRecord* hits,
    CR_GLOBAL TraceStats* stats, CR_GLOBAL const float* times, int hasTimes, __local ulong* packetPool)
{
  CR_PACKET_LOCALS
  const uint i = (uint)get_global_id(0);
  const uint lid = (uint)get_local_id(0);
  const int live = i < nRays;
  const PrimView pv = Trace_PrimView(CR_PRIM_TYPES(CR_PRIM_ARG_) motion);
  const RayRecord rec = Trace_LoadRay(rays, live ? i : 0);
  TraceStats st = {0, 0, 0, 0};
  const Hit hit = Trace_Packet(&pv, CR_TRACE_ONE_ARGS, &rec, Trace_Time(times, hasTimes, live ? i : 0u), live, lid,
                               CR_QUERY_ANYHIT, &st CR_PACKET_ARGS);
  if (live) {
    Trace_StoreHit(hits, i, Hit_ToRecord(&hit, &pv, primIds, CR_QUERY_ANYHIT, CR_QUERY_UNIFIED));
    Trace_StoreStats(stats, i, &st);
  }
}

#endif

#ifndef CR_SOURCE_RAYS
/* Packet variant of the primary rays: the work-group is a CR_PACKET_W x
 * CR_PACKET_H screen tile. */
__kernel __attribute__((reqd_work_group_size(CR_PACKET_W, CR_PACKET_H, 1))) void Trace_PrimaryPacket(
    CR_SCENE_PARAMS, float4 org, camreal4 fwd, camreal4 right, camreal4 up, camreal tanHalf, float tmin, int width,
    int height, CR_GLOBAL HitRecord* hits, CR_GLOBAL TraceStats* stats, __local ulong* packetPool)
{
  CR_PACKET_LOCALS
  const int px = (int)get_global_id(0), py = (int)get_global_id(1);
  const uint lid = (uint)get_local_id(1) * CR_PACKET_W + (uint)get_local_id(0);
  const int live = px < width && py < height;
  const PrimView pv = Trace_PrimView(CR_PRIM_TYPES(CR_PRIM_ARG_) motion);
  const RayRecord rec = Camera_Ray(org, fwd, right, up, tanHalf, tmin, live ? px : 0, live ? py : 0, width, height);
  TraceStats st = {0, 0, 0, 0};
  const Hit hit = Trace_Packet(&pv, CR_TRACE_ONE_ARGS, &rec, 0.0f, live, lid, CR_QUERY_ANYHIT, &st CR_PACKET_ARGS);
  if (live) {
    const uint i = (uint)py * (uint)width + (uint)px;
    Trace_StoreHit(hits, i, Hit_ToRecord(&hit, &pv, primIds, CR_QUERY_ANYHIT, CR_QUERY_UNIFIED));
    Trace_StoreStats(stats, i, &st);
  }
}

#endif

/* The bytes of the packet kernels' pool (their last argument), for the
 * host: one work-item writes them. */
__kernel void Trace_PacketPoolBytes(CR_GLOBAL uint* out) { out[0] = CR_PACKET_POOL_BYTES; }
#endif /* !CR_VARIANT_RAY */
