// vfloat<8>, vint<8>, vbool<8> on AVX2 (included by simd/vec.h when
// compiling with -mavx2). No FMA instruction is used: the scalar kernels
// round after every multiply (-ffp-contract=off).
#pragma once

namespace cr::simd::CR_SIMD_NS {

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
inline vbool<8> operator&(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_and_ps(a.m, b.m)); }
inline vbool<8> operator|(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_or_ps(a.m, b.m)); }
inline vbool<8> operator^(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_xor_ps(a.m, b.m)); }
inline vbool<8> operator!(vbool<8> a)
{
  return vbool<8>(_mm256_xor_ps(a.m, _mm256_castsi256_ps(_mm256_set1_epi32(-1))));
}
inline vbool<8> AndNot(vbool<8> a, vbool<8> b) { return vbool<8>(_mm256_andnot_ps(b.m, a.m)); }
inline bool Any(vbool<8> a) { return _mm256_movemask_ps(a.m) != 0; }
inline bool None(vbool<8> a) { return _mm256_movemask_ps(a.m) == 0; }
inline bool All(vbool<8> a) { return _mm256_movemask_ps(a.m) == 0xFF; }

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
inline vfloat<8> operator+(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_add_ps(a.v, b.v)); }
inline vfloat<8> operator-(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_sub_ps(a.v, b.v)); }
inline vfloat<8> operator*(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_mul_ps(a.v, b.v)); }
inline vfloat<8> operator/(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_div_ps(a.v, b.v)); }
inline vfloat<8> operator-(vfloat<8> a) { return vfloat<8>(_mm256_xor_ps(a.v, _mm256_set1_ps(-0.0f))); }
inline vbool<8> operator<(vfloat<8> a, vfloat<8> b) { return vbool<8>(_mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ)); }
inline vbool<8> operator<=(vfloat<8> a, vfloat<8> b) { return vbool<8>(_mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ)); }
inline vbool<8> operator>(vfloat<8> a, vfloat<8> b) { return vbool<8>(_mm256_cmp_ps(a.v, b.v, _CMP_GT_OQ)); }
inline vbool<8> operator>=(vfloat<8> a, vfloat<8> b) { return vbool<8>(_mm256_cmp_ps(a.v, b.v, _CMP_GE_OQ)); }
inline vbool<8> operator==(vfloat<8> a, vfloat<8> b) { return vbool<8>(_mm256_cmp_ps(a.v, b.v, _CMP_EQ_OQ)); }
inline vbool<8> operator!=(vfloat<8> a, vfloat<8> b) { return vbool<8>(_mm256_cmp_ps(a.v, b.v, _CMP_NEQ_UQ)); }
inline vbool<8> IsNaN(vfloat<8> a) { return vbool<8>(_mm256_cmp_ps(a.v, a.v, _CMP_UNORD_Q)); }
inline vfloat<8> Select(vbool<8> m, vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_blendv_ps(b.v, a.v, m.m)); }
inline vfloat<8> Min(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_min_ps(a.v, b.v)); }
inline vfloat<8> Max(vfloat<8> a, vfloat<8> b) { return vfloat<8>(_mm256_max_ps(a.v, b.v)); }
inline vfloat<8> FMin(vfloat<8> a, vfloat<8> b) { return Select(IsNaN(b), a, Min(a, b)); }
inline vfloat<8> FMax(vfloat<8> a, vfloat<8> b) { return Select(IsNaN(b), a, Max(a, b)); }
inline vfloat<8> Abs(vfloat<8> a) { return vfloat<8>(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), a.v)); }
inline vfloat<8> CopySign(vfloat<8> mag, vfloat<8> sgn)
{
  const __m256 s = _mm256_set1_ps(-0.0f);
  return vfloat<8>(_mm256_or_ps(_mm256_andnot_ps(s, mag.v), _mm256_and_ps(s, sgn.v)));
}
inline vfloat<8> Sqrt(vfloat<8> a) { return vfloat<8>(_mm256_sqrt_ps(a.v)); }
inline float HMin(vfloat<8> a)
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
inline vint<8> operator+(vint<8> a, vint<8> b) { return vint<8>(_mm256_add_epi32(a.v, b.v)); }
inline vint<8> operator*(vint<8> a, vint<8> b) { return vint<8>(_mm256_mullo_epi32(a.v, b.v)); }
inline vbool<8> operator==(vint<8> a, vint<8> b) { return vbool<8>(_mm256_castsi256_ps(_mm256_cmpeq_epi32(a.v, b.v))); }
inline vbool<8> LessUnsigned(vint<8> a, vint<8> b)
{
  const __m256i le = _mm256_cmpeq_epi32(_mm256_min_epu32(a.v, b.v), a.v);
  return AndNot(vbool<8>(_mm256_castsi256_ps(le)), a == b);
}
inline vint<8> Select(vbool<8> m, vint<8> a, vint<8> b)
{
  return vint<8>(_mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b.v), _mm256_castsi256_ps(a.v), m.m)));
}

// vpermilps reads the low two bits of each lane: the axis itself is the control.
inline vint<8> ComponentSelector(vint<8> k) { return k; }
inline vfloat<8> PermuteXYZ(const float* p, vint<8> sel)
{
  return vfloat<8>(_mm256_permutevar_ps(_mm256_broadcast_ps(reinterpret_cast<const __m128*>(p)), sel.v));
}

}  // namespace cr::simd::CR_SIMD_NS
