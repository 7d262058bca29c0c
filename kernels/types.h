/* Shared data layouts: read by the OpenCL compiler and by C++ (host builders,
 * scalar and SIMD backends). Every struct states its byte size; C++ asserts
 * size and offsets, so host and device cannot drift apart.
 *
 * Unified primitive index g: the device stores one array per primitive type and
 * numbers them back to back in type order (CR_PRIM_TYPES): type k holds [begin[k], begin[k + 1]) of PrimRanges, and
 * nothing else computes these offsets (Prim_Is, Prim_Local). References
 * in leaves and cells are such indices, sorted ascending inside each leaf or
 * cell, so they come grouped by type. primIds[g] is the scene-file primitive
 * id of ../shared/FORMATS.md.
 */
#ifndef CELLRAY_KERNELS_TYPES_H
#define CELLRAY_KERNELS_TYPES_H

#include "prelude.h"

CR_NS_BEGIN

#define CR_NO_HIT 0xFFFFFFFFu
#define CR_TRI_REPORT_UV 1u   /* Triangle.flags: the piece is a whole triangle statement */
/* Triangle.flags: edges longer than 16 times their distance from the world
 * origin (host/scene/scene.h TriangleEdgeFlags), whose float edge functions
 * robust mode checks against an error bound (kernels/intersect.h,
 * Triangle_RefineEdges): edge v1-v2 (U), v2-v0 (V), v0-v1 (W). */
#define CR_TRI_LONG_U 2u
#define CR_TRI_LONG_V 4u
#define CR_TRI_LONG_W 8u
#define CR_TRI_LONG_EDGES 14u

/* One record of a .rays file, and the layout rays are uploaded in. 32 bytes. */
typedef struct {
  float org[3];
  float tmin;
  float dir[3];
  float tmax;
} RayRecord;

/* One record of a .hits file, and the layout hits are downloaded in. 16 bytes. */
typedef struct {
  float t;
  uint prim;
  float u;
  float v;
} HitRecord;

/* Sphere: 16 bytes. */
typedef struct {
  float center[3];
  float radius;
} Sphere;

/* Triangle (also every piece of a split polygon or patch): 48 bytes; the pads
 * keep each vertex 16-byte aligned for vector loads. */
typedef struct {
  float v0[3];
  uint flags; /* CR_TRI_REPORT_UV, CR_TRI_LONG_* */
  float v1[3];
  uint pad1;
  float v2[3];
  uint pad2;
} Triangle;

/* Open truncated cone or cylinder between two planes normal to its axis
 * (NFF `c`): 32 bytes. Radii are >= 0 here; which side is visible belongs to
 * the scene's materials. */
typedef struct {
  float base[3];
  float baseRadius;
  float apex[3];
  float apexRadius;
} Cone;

/* Axis-aligned box (NFF extension `box`): its surface, 32 bytes. */
typedef struct {
  float lo[3];
  uint pad0;
  float hi[3];
  uint pad1;
} Box;

/* Quadric surface clipped to a box (NFF extension `quadric`): 64 bytes. The
 * surface is f(x) = x^T Q x + 2 l . x + j = 0 in coordinates x = p - centre
 * relative to the clip box's centre, for |x[i]| <= extent[i] (the half-extents); q holds Q's
 * entries xx, yy, zz, xy, xz, yz (POV-Ray's D, E, F halved), l the halved
 * linear coefficients. */
typedef struct {
  float center[3];
  float j;
  float extent[3];
  float q[6];
  float l[3];
} Quadric;

/* Convex polyhedron (NFF extension `polyhedron N` and N planes): the solid
 * where every plane's n . (p - center) + w <= 0, plane[k] = (n, w) with
 * |n| about 1; count planes, at most CR_POLY_MAX_PLANES (host/prims/
 * polyhedron.cpp refuses more); lo, hi: its float bounds (host use). 560
 * bytes; the tests read the centre and count planes. */
#define CR_POLY_MAX_PLANES 32
typedef struct {
  float center[3];
  uint count;
  float lo[3];
  uint pad0;
  float hi[3];
  uint pad1;
  float plane[CR_POLY_MAX_PLANES][4];
} Polyhedron;

/* SDF block (NFF extension `sdf` ... `sdf end`, kernels/sdf.h): a distance
 * program of `count` operations in postfix order, at most CR_SDF_MAX_OPS,
 * its coordinates about the float centre; leaves push a distance, the
 * combining operations pop two and push one, CR_SDF_REPEAT and
 * CR_SDF_END_REPEAT bracket a domain repetition (host/prims/sdf.cpp checks
 * that no stack exceeds CR_SDF_MAX_STACK). lo, hi: the bound (absolute);
 * eps: the hit threshold; steps: the step budget; relax: the relaxation
 * factor in [1, 2). 64 + 32 CR_SDF_MAX_OPS bytes. */
#define CR_SDF_MAX_OPS 24
#define CR_SDF_MAX_STACK 8
#define CR_SDF_SPHERE 1u
#define CR_SDF_BOX 2u
#define CR_SDF_TORUS 3u
#define CR_SDF_CAPSULE 4u
#define CR_SDF_CYLINDER 5u
#define CR_SDF_UNION 6u
#define CR_SDF_INTERSECTION 7u
#define CR_SDF_DIFFERENCE 8u
#define CR_SDF_SMOOTH_UNION 9u
#define CR_SDF_REPEAT 10u
#define CR_SDF_END_REPEAT 11u
typedef struct {
  uint op;
  float a[7];
} SdfOp;
typedef struct {
  float center[3];
  uint count;
  float lo[3];
  float eps;
  float hi[3];
  uint steps;
  float relax;
  uint pad[3];
  SdfOp op[CR_SDF_MAX_OPS];
} Sdf;

/* CSG solid (NFF extension `csg union|intersection|difference` ... `csg
 * end`, kernels/csg.h): a boolean expression over up to CR_CSG_MAX_LEAVES
 * convex leaf solids (sphere, box, polyhedron, ellipsoidal quadric), in
 * postfix order: node k (byte k of `node`, nNodes of them) is a leaf index
 * below CR_CSG_UNION or one of the operators, which pop two and push one.
 * leaf[i]: the leaf's type CR_PRIM_* in bits 0-7, its first word in bits
 * 8-15; its record is packed in words (kernels/csg.h Csg_Sphere, ...).
 * lo, hi: the solid's float box. 1248 bytes. */
#define CR_CSG_MAX_LEAVES 32
#define CR_CSG_MAX_NODES 64
#define CR_CSG_MAX_WORDS 64
#define CR_CSG_UNION 64u
#define CR_CSG_INTERSECTION 65u
#define CR_CSG_DIFFERENCE 66u
typedef struct {
  float lo[3];
  uint nNodes;
  float hi[3];
  uint nLeaves;
  uint node[CR_CSG_MAX_NODES / 4];
  uint leaf[CR_CSG_MAX_LEAVES];
  float word[CR_CSG_MAX_WORDS][4];
} Csg;

/* The primitive types, one entry each, in unified-index order:
 * X(Type, UPPER, array): the layout `Type` (below), its index constant
 * CR_PRIM_<UPPER>, PrimView's array `array`, and its test Type_Test (and
 * Type_Load, a copy from global memory) in kernels/<type>.h. A new type goes
 * last, so that the primitives of existing scenes keep their g (ties go to
 * the lower g). The device code and its dispatch are generated from this
 * list (kernels/intersect.h, packet.cl). */
#define CR_PRIM_TYPES(X) \
  X(Sphere, SPHERE, spheres) X(Triangle, TRIANGLE, triangles) X(Cone, CONE, cones) X(Box, BOX, boxes) \
      X(Quadric, QUADRIC, quadrics) X(Polyhedron, POLYHEDRON, polyhedra) X(Sdf, SDF, sdfs) X(Csg, CSG, csgs)
#define CR_PRIM_SPHERE 0u
#define CR_PRIM_TRIANGLE 1u
#define CR_PRIM_CONE 2u
#define CR_PRIM_BOX 3u
#define CR_PRIM_QUADRIC 4u
#define CR_PRIM_POLYHEDRON 5u
#define CR_PRIM_SDF 6u
#define CR_PRIM_CSG 7u
#define CR_NUM_PRIM_TYPES 8u
/* Whether a kernel is built for a type: CR_HAS_<UPPER> is 1 or 0 (default
 * 1, in the type's header; an OpenCL program is built with only its
 * scene's types, -DCR_HAS_<UPPER>=0 for the others). CR_IF(UPPER, code)
 * keeps the code only for a type the kernel is built for, so that the
 * generated dispatch compiles nothing of an absent type. OpenCL C 1.2 has
 * no variadic macros (NVIDIA's compiler rejects them), so `code` is one
 * macro argument: any comma in it must sit inside parentheses; code whose
 * commas come from a macro's expansion selects CR_IF_1/CR_IF_0 directly,
 * CR_CAT(CR_IF_, flag)(MACRO), which expands MACRO last. */
#define CR_CAT_(a, b) a##b
#define CR_CAT(a, b) CR_CAT_(a, b)
#define CR_IF_1(code) code
#define CR_IF_0(code)
#define CR_IF(U, code) CR_CAT(CR_IF_, CR_HAS_##U)(code)

/* Where each type's unified indices begin: type k holds [begin[k],
 * begin[k + 1]), begin[CR_NUM_PRIM_TYPES] is the number of primitives;
 * padded to a multiple of 16 bytes (48 for 8 to 11 types). */
#define CR_PRIM_RANGE_SLOTS ((CR_NUM_PRIM_TYPES + 4u) & ~3u)
typedef struct {
  uint begin[CR_PRIM_RANGE_SLOTS];
} PrimRanges;

/* Whether g is of type k, and its index in that type's array. */
CR_FUNC int Prim_Is(const PrimRanges* r, uint k, uint g) { return g >= r->begin[k] && g < r->begin[k + 1u]; }
CR_FUNC uint Prim_Local(const PrimRanges* r, uint k, uint g) { return g - r->begin[k]; }
CR_FUNC uint Prim_End(const PrimRanges* r, uint k) { return r->begin[k + 1u]; }
CR_FUNC uint Prim_Count(const PrimRanges* r, uint k) { return r->begin[k + 1u] - r->begin[k]; }

/* The structures, one entry each, in the order of their `accel` argument
 * values (CR_ACCEL_ID_*) and of the host's AccelKind:
 * X(Name, UPPER, lower, Header, Node): the flat layout (one Header record,
 * an array of Node, the references), its traversals Name_Trace(header,
 * nodes, refs, pv, ray, hit, anyHit, stats) in kernels/<lower>.h and
 * NamePacket_Trace in kernels/<lower>_packet.cl (both included by
 * kernels/accels.h), its build option CR_ACCEL_<UPPER>, its builder
 * Build<Name> (host/accel/), its SIMD kernels Select<Name>Kernel (simd/). The
 * kernel arguments, the dispatch of every backend and the lists the CLI,
 * bench and tests iterate are generated from this list. */
#define CR_ACCEL_TYPES(X)                                      \
  X(Grid, GRID, grid, GridHeader, uint)                        \
  X(Octree, OCTREE, octree, OctreeHeader, OctreeNode)          \
  X(BVH, BVH, bvh, BVHHeader, BVHNode)                         \
  X(HGrid, HGRID, hgrid, GridHeader, GridHeader)
#define CR_ACCEL_ID_(N, U, l, H, Nd) CR_ACCEL_ID_##U,
enum { CR_ACCEL_TYPES(CR_ACCEL_ID_) CR_NUM_ACCEL_TYPES };
#undef CR_ACCEL_ID_

/* BVH header, 16 bytes: the counts of its arrays (the stack traversal needs
 * none; the record keeps the structures' flat layouts alike). parents: where
 * the references array holds each node's parent (node 0's is 0), for the
 * stackless walk (kernels/bvh.h, CR_BVH_STACKLESS); 0 where it holds none. */
typedef struct {
  uint nNodes;
  uint nRefs;
  uint parents;
  uint pad;
} BVHHeader;

/* BVH node, 32 bytes (pbrt's LinearBVHNode shape). count == 0: interior node
 * whose children are nodes `first` and `first + 1`; count > 0: leaf holding
 * references [first, first + count). Node 0 is the root. */
typedef struct {
  float bmin[3];
  uint first;
  float bmax[3];
  uint count;
} BVHNode;

/* Uniform grid header, 64 bytes. Cell (x, y, z) has index
 * x + res[0] * (y + res[1] * z); its references are
 * refs[cellStart[i] .. cellStart[i + 1]) (compressed row layout, nCells + 1
 * offsets). Cell planes are bmin + i * cellSize, computed only by
 * Grid_Plane() so builder and traversal agree to the bit. Also the top grid
 * and each grid of the hierarchical grid (kernels/hgrid.h), where `first`
 * tells where its cell offsets begin in refs (0 elsewhere). */
typedef struct {
  float bmin[3];
  uint nCells;
  float bmax[3];
  uint nRefs;
  float cellSize[3];
  uint first;
  uint res[3];
  /* Hierarchical grid: the distance by which cells took their references
   * (0 in the uniform grid, which does not read it). */
  float margin;
} GridHeader;

/* Hierarchical grid (kernels/hgrid.h): levels below the root grid (the
 * builder's limit and the walk's stack depth), the marker of a cell that is
 * a child grid (its first item is CR_HGRID_CHILD | node index, then the
 * number of the cell's references, those, and its large references), and
 * the bound on a float walk's error per unit
 * of distance travelled (2^-21: 8 units in the last place, HGrid_Reach). */
#define CR_HGRID_MAX_DEPTH 4
#define CR_HGRID_CHILD 0x80000000u
#define CR_HGRID_RAY_ERR 4.76837158203125e-07f
/* Entries of the hierarchical grid walk's mailbox (a power of two;
 * kernels/hgrid.h). */
#define CR_HGRID_MAILBOX 8
/* The least distance at which the walk jumps over empty cells (kernels/hgrid.h
 * HGrid_Skip; 3 measured 1.015 of 2's SIMD time, docs/BENCHMARKS.md). */
#define CR_HGRID_SKIP_MIN 2

/* Octree node, 16 bytes. childMask != 0: interior node; its non-empty children
 * are stored in octant order starting at `first`, child of octant o at
 * first + popcount(childMask & ((1 << o) - 1)); octant bit 0 is +x, 1 is +y,
 * 2 is +z. childMask == 0: leaf with references [first, first + count);
 * with CR_OCTREE_LEAF_BOXES in the header's flags a leaf with count > 0 is
 * preceded in the references by its box, refs[first - 6 .. first): lo x y z,
 * hi x y z as float bits (the union of its primitives' bounds clipped to the
 * cell, rounded outward). `depth` is informative (the level of the node,
 * root 0). */
typedef struct {
  uint first;
  uint count;
  uint childMask;
  uint depth;
} OctreeNode;

/* Octree header, 32 bytes: a cube [rootMin, rootMin + rootSize]^3. Planes are
 * rootMin + i * (rootSize * 2^-level), computed only by Octree_Plane().
 * flags: CR_OCTREE_MAILBOX_ON (--octree-mailbox on: the walks skip a
 * primitive the ray has tested in an earlier leaf, kernels/octree.h);
 * CR_OCTREE_MARGIN_RAY (--octree-margin ray: cells take their references
 * without the scene-relative padding, and the walks widen each cell's
 * parameter interval by the ray's own rounding instead, Octree_TraceRay);
 * CR_OCTREE_LEAF_BOXES (--octree-leaf-box on, with the ray's margins: each
 * leaf's box precedes its references, and the walks test a leaf's
 * primitives only for rays that enter the box, Octree_Leaf). */
typedef struct {
  float rootMin[3];
  float rootSize;
  uint nNodes;
  uint nRefs;
  uint maxDepth;
  uint flags;
} OctreeHeader;
#define CR_OCTREE_MAILBOX_ON 1u
#define CR_OCTREE_MARGIN_RAY 2u
#define CR_OCTREE_LEAF_BOXES 4u
/* Words of a leaf's box in the references (CR_OCTREE_LEAF_BOXES). */
#define CR_OCTREE_BOX_WORDS 6u
/* Entries of the octree walk's mailbox when it is on (a power of two). */
#define CR_OCTREE_MAILBOX 8

CR_NS_END

#ifdef __cplusplus
#include <cstddef>
namespace cr {
static_assert(sizeof(RayRecord) == 32 && offsetof(RayRecord, tmin) == 12 && offsetof(RayRecord, tmax) == 28);
static_assert(sizeof(HitRecord) == 16 && offsetof(HitRecord, prim) == 4 && offsetof(HitRecord, v) == 12);
static_assert(sizeof(Sphere) == 16);
static_assert(sizeof(Triangle) == 48 && offsetof(Triangle, v1) == 16 && offsetof(Triangle, v2) == 32);
static_assert(sizeof(Cone) == 32 && offsetof(Cone, apex) == 16);
static_assert(sizeof(Box) == 32 && offsetof(Box, hi) == 16);
static_assert(sizeof(Quadric) == 64 && offsetof(Quadric, extent) == 16 && offsetof(Quadric, q) == 28);
static_assert(sizeof(Polyhedron) == 48 + 16 * CR_POLY_MAX_PLANES && offsetof(Polyhedron, plane) == 48);
static_assert(sizeof(Sdf) == 64 + 32 * CR_SDF_MAX_OPS && offsetof(Sdf, op) == 64);
static_assert(sizeof(Csg) == 224 + 16 * CR_CSG_MAX_WORDS && offsetof(Csg, word) == 224);
static_assert(sizeof(PrimRanges) % 16 == 0);
static_assert(sizeof(BVHHeader) == 16);
static_assert(sizeof(BVHNode) == 32 && offsetof(BVHNode, first) == 12 && offsetof(BVHNode, count) == 28);
static_assert(sizeof(GridHeader) == 64 && offsetof(GridHeader, res) == 48);
static_assert(sizeof(OctreeNode) == 16);
static_assert(sizeof(OctreeHeader) == 32);
}  // namespace cr
#endif

#endif /* CELLRAY_KERNELS_TYPES_H */
