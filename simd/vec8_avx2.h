// vfloat<8>, vint<8>, vbool<8> on AVX2 (included by simd/vec.h when
// compiling with -mavx2; with AVX-512VL too, where vbool<8> is a mask
// register). No FMA instruction is used: the scalar kernels
// round after every multiply (-ffp-contract=off).
#pragma once

namespace cr::simd::CR_SIMD_NS {

#if defined(__AVX512VL__)
// With AVX-512VL (the avx512 unit, simd/vec.h) a lane mask lives in a mask
// register: compares write it, blends and masked moves read it, and its bits
// are the mask itself (no movemask).
template <>
struct vbool<8> {
  __mmask8 k;
  vbool() = default;
  explicit vbool(__mmask8 x) : k(x) {}
  explicit vbool(bool b) : k(b ? __mmask8(0xFF) : __mmask8(0)) {}
  static vbool FromBits(unsigned bits) { return vbool(__mmask8(bits)); }
  unsigned Bits() const { return unsigned(k); }
  static constexpr unsigned kAll = 0xFFu;
};
CR_SIMD_INLINE vbool<8> operator&(vbool<8> a, vbool<8> b) { return vbool<8>(__mmask8(a.k & b.k)); }
CR_SIMD_INLINE vbool<8> operator|(vbool<8> a, vbool<8> b) { return vbool<8>(__mmask8(a.k | b.k)); }
CR_SIMD_INLINE vbool<8> operator^(vbool<8> a, vbool<8> b) { return vbool<8>(__mmask8(a.k ^ b.k)); }
CR_SIMD_INLINE vbool<8> operator!(vbool<8> a) { return vbool<8>(__mmask8(~a.k)); }
CR_SIMD_INLINE vbool<8> AndNot(vbool<8> a, vbool<8> b) { return vbool<8>(__mmask8(a.k & ~b.k)); }
CR_SIMD_INLINE bool Any(vbool<8> a) { return a.k != 0; }
CR_SIMD_INLINE bool None(vbool<8> a) { return a.k == 0; }
CR_SIMD_INLINE bool All(vbool<8> a) { return a.k == 0xFF; }
template <int P>
CR_SIMD_INLINE vbool<8> CmpPs8(__m256 a, __m256 b) { return vbool<8>(_mm256_cmp_ps_mask(a, b, P)); }
CR_SIMD_INLINE vbool<8> CmpEq8(__m256i a, __m256i b) { return vbool<8>(_mm256_cmpeq_epi32_mask(a, b)); }
CR_SIMD_INLINE vbool<8> CmpGt8(__m256i a, __m256i b) { return vbool<8>(_mm256_cmpgt_epi32_mask(a, b)); }
CR_SIMD_INLINE __m256 Blend8(vbool<8> m, __m256 a, __m256 b) { return _mm256_mask_blend_ps(m.k, b, a); }
CR_SIMD_INLINE __m256i MaskZ8(vbool<8> m, __m256i a) { return _mm256_maskz_mov_epi32(m.k, a); }
#else
template <>
struct vbool<8> {
  __m256 m;
  vbool() = default;
  explicit vbool(__m256 x) : m(x) {}
  explicit vbool(bool b) : m(_mm256_castsi256_ps(_mm256_set1_epi32(b ? -1 : 0))) {}
  static vbool FromBits(unsigned bits)
  {
    const __m256i lane = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    const __m256i b = _mm256_and_si256(_mm256_set1_epi32(int(bits)), lane);
    return vbool(_mm256_castsi256_ps(_mm256_cmpeq_epi32(b, lane)));
  }
  unsigned Bits() const { return unsigned(_mm256_movemask_ps(m)); }
  static constexpr unsigned kAll = 0xFFu;
};
CR_SIMD_INLINE vbool<8> operator&(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_and_ps(a.m, b.m)); }
CR_SIMD_INLINE vbool<8> operator|(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_or_ps(a.m, b.m)); }
CR_SIMD_INLINE vbool<8> operator^(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_xor_ps(a.m, b.m)); }
CR_SIMD_INLINE vbool<8> operator!(vbool<8> a)
{
  return vbool<8>(_mm256_xor_ps(a.m, _mm256_castsi256_ps(_mm256_set1_epi32(-1))));
}
CR_SIMD_INLINE vbool<8> AndNot(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_andnot_ps(b.m, a.m)); }
CR_SIMD_INLINE bool Any(vbool<8> a) { return _mm256_movemask_ps(a.m) != 0; }
CR_SIMD_INLINE bool None(vbool<8> a) { return _mm256_movemask_ps(a.m) == 0; }
CR_SIMD_INLINE bool All(vbool<8> a) { return _mm256_movemask_ps(a.m) == 0xFF; }

template <int P>
CR_SIMD_INLINE vbool<8> CmpPs8(__m256 a, __m256 b) { return vbool<8>(_mm256_cmp_ps(a, b, P)); }
CR_SIMD_INLINE vbool<8> CmpEq8(__m256i a, __m256i b) { return vbool<8>(_mm256_castsi256_ps(_mm256_cmpeq_epi32(a, b))); }
CR_SIMD_INLINE vbool<8> CmpGt8(__m256i a, __m256i b) { return vbool<8>(_mm256_castsi256_ps(_mm256_cmpgt_epi32(a, b))); }
// a where m, else b.
CR_SIMD_INLINE __m256 Blend8(vbool<8> m, __m256 a, __m256 b) { return _mm256_blendv_ps(b, a, m.m); }
// a where m, else 0.
CR_SIMD_INLINE __m256i MaskZ8(vbool<8> m, __m256i a) { return _mm256_and_si256(_mm256_castps_si256(m.m), a); }
#endif

template <>
struct vfloat<8> {
  __m256 v;
  static constexpr int kSize = 8;
  vfloat() = default;
  explicit vfloat(__m256 x) : v(x) {}
  vfloat(float x) : v(_mm256_set1_ps(x)) {}
  static vfloat Load(const float* p) { return vfloat(_mm256_loadu_ps(p)); }
  void Store(float* p) const { _mm256_storeu_ps(p, v); }
  float operator[](int i) const
  {
    alignas(32) float a[8];
    _mm256_store_ps(a, v);
    return a[i];
  }
};
CR_SIMD_INLINE vfloat<8> operator+(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_add_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<8> operator-(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_sub_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<8> operator*(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_mul_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<8> operator/(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_div_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<8> operator-(vfloat<8> a) { return vfloat<8>(_mm256_xor_ps(a.v, _mm256_set1_ps(-0.0f))); }
CR_SIMD_INLINE vbool<8> operator<(vfloat<8> a, vfloat<8> b) { return CmpPs8<_CMP_LT_OQ>(a.v, b.v); }
CR_SIMD_INLINE vbool<8> operator<=(vfloat<8> a, vfloat<8> b) { return CmpPs8<_CMP_LE_OQ>(a.v, b.v); }
CR_SIMD_INLINE vbool<8> operator>(vfloat<8> a, vfloat<8> b) { return CmpPs8<_CMP_GT_OQ>(a.v, b.v); }
CR_SIMD_INLINE vbool<8> operator>=(vfloat<8> a, vfloat<8> b) { return CmpPs8<_CMP_GE_OQ>(a.v, b.v); }
CR_SIMD_INLINE vbool<8> operator==(vfloat<8> a, vfloat<8> b) { return CmpPs8<_CMP_EQ_OQ>(a.v, b.v); }
CR_SIMD_INLINE vbool<8> operator!=(vfloat<8> a, vfloat<8> b) { return CmpPs8<_CMP_NEQ_UQ>(a.v, b.v); }
CR_SIMD_INLINE vbool<8> IsNaN(vfloat<8> a) { return CmpPs8<_CMP_UNORD_Q>(a.v, a.v); }
CR_SIMD_INLINE vfloat<8> Select(vbool<8> m, vfloat<8> a, vfloat<8> b)
{
  return vfloat<8>(Blend8(m, a.v, b.v));
}
CR_SIMD_INLINE vfloat<8> Min(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_min_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<8> Max(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_max_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<8> FMin(vfloat<8> a, vfloat<8> b) { return Select(IsNaN(b), a, Min(a, b)); }
CR_SIMD_INLINE vfloat<8> FMax(vfloat<8> a, vfloat<8> b) { return Select(IsNaN(b), a, Max(a, b)); }
CR_SIMD_INLINE vfloat<8> Abs(vfloat<8> a) { return vfloat<8>(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), a.v)); }
CR_SIMD_INLINE vfloat<8> CopySign(vfloat<8> mag, vfloat<8> sgn)
{
  const __m256 s = _mm256_set1_ps(-0.0f);
  return vfloat<8>(_mm256_or_ps(_mm256_andnot_ps(s, mag.v), _mm256_and_ps(s, sgn.v)));
}
CR_SIMD_INLINE vfloat<8> Sqrt(vfloat<8> a) { return vfloat<8>(_mm256_sqrt_ps(a.v)); }
// a b - p exactly, for p = a b rounded: one FMA (the same bits as Dekker's
// split, which the kernels use: the error is representable and exact).
CR_SIMD_INLINE vfloat<8> ProductError(vfloat<8> a, vfloat<8> b, vfloat<8> p)
{
  return vfloat<8>(_mm256_fmsub_ps(a.v, b.v, p.v));
}
CR_SIMD_INLINE float HMin(vfloat<8> a)
{
  __m128 m = _mm_min_ps(_mm256_castps256_ps128(a.v), _mm256_extractf128_ps(a.v, 1));
  m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
  m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
  return _mm_cvtss_f32(m);
}

template <>
struct vint<8> {
  __m256i v;
  static constexpr int kSize = 8;
  vint() = default;
  explicit vint(__m256i x) : v(x) {}
  vint(int x) : v(_mm256_set1_epi32(x)) {}
  static vint Load(const std::uint32_t* p) { return vint(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))); }
  static vint Lanes() { return vint(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)); }
  void Store(std::uint32_t* p) const { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
  std::uint32_t operator[](int i) const
  {
    alignas(32) std::uint32_t a[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(a), v);
    return a[i];
  }
};
CR_SIMD_INLINE vint<8> operator+(vint<8> a, vint<8> b) { return vint<8>(_mm256_add_epi32(a.v, b.v)); }
CR_SIMD_INLINE vint<8> operator*(vint<8> a, vint<8> b) { return vint<8>(_mm256_mullo_epi32(a.v, b.v)); }
CR_SIMD_INLINE vbool<8> operator==(vint<8> a, vint<8> b) { return CmpEq8(a.v, b.v); }
CR_SIMD_INLINE vbool<8> LessUnsigned(vint<8> a, vint<8> b)
{
  return AndNot(CmpEq8(_mm256_min_epu32(a.v, b.v), a.v), a == b);
}
CR_SIMD_INLINE vint<8> Select(vbool<8> m, vint<8> a, vint<8> b)
{
  return vint<8>(_mm256_castps_si256(Blend8(m, _mm256_castsi256_ps(a.v), _mm256_castsi256_ps(b.v))));
}
CR_SIMD_INLINE vint<8> operator-(vint<8> a, vint<8> b) { return vint<8>(_mm256_sub_epi32(a.v, b.v)); }
CR_SIMD_INLINE vbool<8> operator<(vint<8> a, vint<8> b) { return CmpGt8(b.v, a.v); }
CR_SIMD_INLINE vbool<8> operator>(vint<8> a, vint<8> b) { return CmpGt8(a.v, b.v); }
// lo = base[idx], hi = base[idx + 1] per lane (idx >= 0): one 8-byte load per lane.
CR_SIMD_INLINE void GatherPairs(const std::uint32_t* base, vint<8> idx, vint<8>& lo, vint<8>& hi)
{
  alignas(32) std::uint32_t i[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(i), idx.v);
  auto pair = [&](int a, int b) {
    const __m128d q = _mm_castsi128_pd(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(base + i[a])));
    return _mm_castpd_ps(_mm_loadh_pd(q, reinterpret_cast<const double*>(base + i[b])));
  };
  const __m256 a = _mm256_set_m128(pair(4, 5), pair(0, 1));  // lanes 0 1 | 4 5 as lo hi pairs
  const __m256 b = _mm256_set_m128(pair(6, 7), pair(2, 3));  // lanes 2 3 | 6 7
  lo = vint<8>(_mm256_castps_si256(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0))));
  hi = vint<8>(_mm256_castps_si256(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1))));
}
// base[idx] lane by lane, by scalar loads (as GatherPairs: the AVX2 gather
// instruction is microcoded and slower on AMD's cores).
CR_SIMD_INLINE vint<8> Gather(const std::uint32_t* base, vint<8> idx)
{
  alignas(32) std::uint32_t i[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(i), idx.v);
  return vint<8>(_mm256_setr_epi32(int(base[i[0]]), int(base[i[1]]), int(base[i[2]]), int(base[i[3]]),
                                   int(base[i[4]]), int(base[i[5]]), int(base[i[6]]), int(base[i[7]])));
}
// a & b, and a >> n (logical, n < 32), lane by lane.
CR_SIMD_INLINE vint<8> And(vint<8> a, vint<8> b) { return vint<8>(_mm256_and_si256(a.v, b.v)); }
CR_SIMD_INLINE vint<8> ShiftRight(vint<8> a, vint<8> n) { return vint<8>(_mm256_srlv_epi32(a.v, n.v)); }
CR_SIMD_INLINE vint<8> MaskedOrZero(vbool<8> m, vint<8> a)
{
  return vint<8>(MaskZ8(m, a.v));
}
CR_SIMD_INLINE vfloat<8> ToFloat(vint<8> a) { return vfloat<8>(_mm256_cvtepi32_ps(a.v)); }
CR_SIMD_INLINE vint<8> FloorToInt(vfloat<8> x) { return vint<8>(_mm256_cvttps_epi32(_mm256_floor_ps(x.v))); }

// Eight rows of 8 floats (e.g. RayRecords) transposed: out[j] lane l = rows[l][j].
CR_SIMD_INLINE void LoadTransposed(const float* const rows[8], vfloat<8> out[8])
{
  __m256 r[8];
  for (int i = 0; i < 8; ++i) r[i] = _mm256_loadu_ps(rows[i]);
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 s0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 s2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 s4 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s5 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 s6 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s7 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2));
  out[0] = vfloat<8>(_mm256_permute2f128_ps(s0, s4, 0x20));
  out[1] = vfloat<8>(_mm256_permute2f128_ps(s1, s5, 0x20));
  out[2] = vfloat<8>(_mm256_permute2f128_ps(s2, s6, 0x20));
  out[3] = vfloat<8>(_mm256_permute2f128_ps(s3, s7, 0x20));
  out[4] = vfloat<8>(_mm256_permute2f128_ps(s0, s4, 0x31));
  out[5] = vfloat<8>(_mm256_permute2f128_ps(s1, s5, 0x31));
  out[6] = vfloat<8>(_mm256_permute2f128_ps(s2, s6, 0x31));
  out[7] = vfloat<8>(_mm256_permute2f128_ps(s3, s7, 0x31));
}

// vpermilps reads the low two bits of each lane: the axis itself is the control.
CR_SIMD_INLINE vint<8> ComponentSelector(vint<8> k) { return k; }
CR_SIMD_INLINE vfloat<8> PermuteXYZ(const float* p, vint<8> sel)
{
  return vfloat<8>(_mm256_permutevar_ps(_mm256_broadcast_ps(reinterpret_cast<const __m128*>(p)), sel.v));
}

// MaskedLanes of vec4_sse4.h on 8 lanes.
CR_SIMD_INLINE unsigned MaskedLanes(__m256i bits, std::uint32_t mask)
{
  const __m256i m = _mm256_and_si256(bits, _mm256_set1_epi32(static_cast<int>(mask)));
  return unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(m, _mm256_setzero_si256())))) ^ 0xFFu;
}
CR_SIMD_INLINE unsigned MaskedLanes(vfloat<8> x, std::uint32_t mask)
{
  return MaskedLanes(_mm256_castps_si256(x.v), mask);
}
CR_SIMD_INLINE unsigned MaskedLanes(vint<8> x, std::uint32_t mask) { return MaskedLanes(x.v, mask); }

}  // namespace cr::simd::CR_SIMD_NS
