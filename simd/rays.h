// The rays of the SIMD kernels: N rays in the lanes (RayPacket, HitPacket:
// the packet kernels) and one ray broadcast to the K lanes of a pack of
// primitives (PackRay: the single-ray kernels). Prepared with the
// operations of Ray_Init (kernels/ray.h), lane by lane.
#pragma once

#include "simd/intersect_simd.h"

namespace cr::simd::CR_SIMD_NS {

template <int N>
struct RayPacket {
  vfloat<N> org[3], dir[3], inv[3];
  vbool<N> invNeg[3];  // inv < 0: the near plane is bmax
  vfloat<N> tmin;
  vfloat<N> dd;       // d.d, for the sphere test
  vfloat<N> s[3];     // shear constants sx, sy, sz
  vint<N> k[3];       // kx, ky, kz
  vint<N> sel[3];     // ComponentSelector of kx, ky, kz
  vfloat<N> orgK[3];  // org[kx], org[ky], org[kz]
  // When every lane has the same kx, ky, kz (coherent packets), they are
  // kScalar, and triangle tests broadcast components instead of permuting.
  bool kUniform;
  int kScalar[3];
  // When every lane has the same direction signs (coherent packets), the
  // near plane of axis a is node float nearOff[a] for all lanes (bmin[a] or
  // bmax[a] as BVHNode lays them out), and the per-lane plane choice is skipped.
  bool sameSigns;
  int nearOff[3], farOff[3];
  // An any-hit (occlusion) query: Ray::anyHit of kernels/ray.h for every lane.
  bool anyHit = false;
};

template <int N>
struct HitPacket {
  vfloat<N> t, u, v;
  vint<N> g;
};

// Ray_Init of kernels/ray.h on all lanes at once, from the N records (a
// lane's record pointer may repeat another's to pad the packet); hits as
// Hit_Init leaves them. Same operations as Ray_Init, lane by lane: the
// reciprocals and shear constants are IEEE divisions, the dominant axis kz
// comes from the same comparisons (so NaN components choose as they do).
template <int N>
CR_SIMD_INLINE void RayPacket_Init(RayPacket<N>& p, HitPacket<N>& h, const RayRecord* const recs[N])
{
  static_assert(sizeof(RayRecord) == 8 * sizeof(float));
  const float* rows[N];
  for (int l = 0; l < N; ++l) rows[l] = recs[l]->org;
  vfloat<N> c[8];  // org x y z, tmin, dir x y z, tmax
  LoadTransposed(rows, c);
  const vfloat<N>* org = c;
  const vfloat<N>* dir = c + 4;
  for (int a = 0; a < 3; ++a) {
    p.org[a] = org[a];
    p.dir[a] = dir[a];
    p.inv[a] = vfloat<N>(1.0f) / dir[a];
    p.invNeg[a] = p.inv[a] < vfloat<N>(0.0f);
  }
  p.tmin = c[3];
  p.dd = Dot3N<N>(p.dir, p.dir);
  h.t = c[7];
  h.u = vfloat<N>(0.0f);
  h.v = vfloat<N>(0.0f);
  h.g = vint<N>(static_cast<int>(CR_NO_HIT));

  const vfloat<N> ax = Abs(dir[0]), ay = Abs(dir[1]), az = Abs(dir[2]);
  const vint<N> k0(0), k1(1), k2(2);
  const vint<N> kz = Select(ax > ay, Select(ax > az, k0, k2), Select(ay > az, k1, k2));
  vint<N> kx = Select(kz == k2, k0, kz + k1);
  vint<N> ky = Select(kx == k2, k0, kx + k1);
  auto pick = [&](const vfloat<N>* v, vint<N> k) { return Select(k == k0, v[0], Select(k == k1, v[1], v[2])); };
  const vfloat<N> dz = pick(dir, kz);
  const vbool<N> flip = dz < vfloat<N>(0.0f);
  const vint<N> kxs = Select(flip, ky, kx);
  ky = Select(flip, kx, ky);
  kx = kxs;
  p.s[0] = pick(dir, kx) / dz;
  p.s[1] = pick(dir, ky) / dz;
  p.s[2] = vfloat<N>(1.0f) / dz;
  p.k[0] = kx;
  p.k[1] = ky;
  p.k[2] = kz;
  for (int j = 0; j < 3; ++j) {
    p.sel[j] = ComponentSelector(p.k[j]);
    p.orgK[j] = pick(org, p.k[j]);
  }
  p.kUniform = true;
  for (int j = 0; j < 3; ++j) {
    const int first = static_cast<int>(p.k[j][0]);
    p.kScalar[j] = first;
    p.kUniform = p.kUniform && All(p.k[j] == vint<N>(first));
  }
  p.sameSigns = true;
  for (int a = 0; a < 3; ++a) {
    const unsigned neg = p.invNeg[a].Bits();
    p.sameSigns = p.sameSigns && (neg == 0 || neg == vbool<N>::kAll);
    p.nearOff[a] = neg ? 4 + a : a;  // BVHNode: bmin at floats 0..2, bmax at 4..6
    p.farOff[a] = neg ? a : 4 + a;
  }
}

// The ray broadcast to the K lanes of the primitive packs.
template <int K>
struct PackRay {
  vfloat<K> org[3], dir[3];
  vfloat<K> orgK[3];  // org[kx], org[ky], org[kz]
  vfloat<K> s[3];
  vfloat<K> tmin;
  vfloat<K> dd;  // d.d, for the sphere test
  int k[3];
  bool anyHit = false;  // Ray::anyHit; set by the walk that knows the query
};

template <int K>
CR_SIMD_INLINE void PackRay_Init(PackRay<K>& pr, const Ray& r)
{
  pr.k[0] = r.kx;
  pr.k[1] = r.ky;
  pr.k[2] = r.kz;
  for (int a = 0; a < 3; ++a) {
    pr.org[a] = vfloat<K>(r.org[a]);
    pr.dir[a] = vfloat<K>(r.dir[a]);
    pr.orgK[a] = vfloat<K>(r.org[pr.k[a]]);
  }
  pr.s[0] = vfloat<K>(r.sx);
  pr.s[1] = vfloat<K>(r.sy);
  pr.s[2] = vfloat<K>(r.sz);
  pr.tmin = vfloat<K>(r.tmin);
  pr.dd = Dot3N<K>(pr.dir, pr.dir);
}

}  // namespace cr::simd::CR_SIMD_NS
