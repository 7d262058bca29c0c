// vfloat<4>, vint<4>, vbool<4> on SSE4.1 (included by simd/vec.h only).
#pragma once

namespace cr::simd::CR_SIMD_NS {

template <>
struct vbool<4> {
  __m128 m;
  vbool() = default;
  explicit vbool(__m128 x) : m(x) {}
  explicit vbool(bool b) : m(_mm_castsi128_ps(_mm_set1_epi32(b ? -1 : 0))) {}
  // Lane i is set when bit i of `bits` is.
  static vbool FromBits(unsigned bits)
  {
    const __m128i lane = _mm_setr_epi32(1, 2, 4, 8);
    const __m128i b = _mm_and_si128(_mm_set1_epi32(int(bits)), lane);
    return vbool(_mm_castsi128_ps(_mm_cmpeq_epi32(b, lane)));
  }
  unsigned Bits() const { return unsigned(_mm_movemask_ps(m)); }
  static constexpr unsigned kAll = 0xFu;
};
CR_SIMD_INLINE vbool<4> operator&(vbool<4> a, vbool<4> b) { return vbool<4>(_mm_and_ps(a.m, b.m)); }
CR_SIMD_INLINE vbool<4> operator|(vbool<4> a, vbool<4> b) { return vbool<4>(_mm_or_ps(a.m, b.m)); }
CR_SIMD_INLINE vbool<4> operator^(vbool<4> a, vbool<4> b) { return vbool<4>(_mm_xor_ps(a.m, b.m)); }
CR_SIMD_INLINE vbool<4> operator!(vbool<4> a)
{
  return vbool<4>(_mm_xor_ps(a.m, _mm_castsi128_ps(_mm_set1_epi32(-1))));
}
// a and not b.
CR_SIMD_INLINE vbool<4> AndNot(vbool<4> a, vbool<4> b) { return vbool<4>(_mm_andnot_ps(b.m, a.m)); }
CR_SIMD_INLINE bool Any(vbool<4> a) { return _mm_movemask_ps(a.m) != 0; }
CR_SIMD_INLINE bool None(vbool<4> a) { return _mm_movemask_ps(a.m) == 0; }
CR_SIMD_INLINE bool All(vbool<4> a) { return _mm_movemask_ps(a.m) == 0xF; }

template <>
struct vfloat<4> {
  __m128 v;
  static constexpr int kSize = 4;
  vfloat() = default;
  explicit vfloat(__m128 x) : v(x) {}
  vfloat(float x) : v(_mm_set1_ps(x)) {}  // broadcast (implicit, as in Embree)
  static vfloat Load(const float* p) { return vfloat(_mm_loadu_ps(p)); }
  void Store(float* p) const { _mm_storeu_ps(p, v); }
  float operator[](int i) const
  {
    alignas(16) float a[4];
    _mm_store_ps(a, v);
    return a[i];
  }
};
CR_SIMD_INLINE vfloat<4> operator+(vfloat<4> a, vfloat<4> b) { return vfloat<4>(_mm_add_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<4> operator-(vfloat<4> a, vfloat<4> b) { return vfloat<4>(_mm_sub_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<4> operator*(vfloat<4> a, vfloat<4> b) { return vfloat<4>(_mm_mul_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<4> operator/(vfloat<4> a, vfloat<4> b) { return vfloat<4>(_mm_div_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<4> operator-(vfloat<4> a) { return vfloat<4>(_mm_xor_ps(a.v, _mm_set1_ps(-0.0f))); }
CR_SIMD_INLINE vbool<4> operator<(vfloat<4> a, vfloat<4> b) { return vbool<4>(_mm_cmplt_ps(a.v, b.v)); }
CR_SIMD_INLINE vbool<4> operator<=(vfloat<4> a, vfloat<4> b) { return vbool<4>(_mm_cmple_ps(a.v, b.v)); }
CR_SIMD_INLINE vbool<4> operator>(vfloat<4> a, vfloat<4> b) { return vbool<4>(_mm_cmpgt_ps(a.v, b.v)); }
CR_SIMD_INLINE vbool<4> operator>=(vfloat<4> a, vfloat<4> b) { return vbool<4>(_mm_cmpge_ps(a.v, b.v)); }
CR_SIMD_INLINE vbool<4> operator==(vfloat<4> a, vfloat<4> b) { return vbool<4>(_mm_cmpeq_ps(a.v, b.v)); }
// C's !=: true when either operand is NaN.
CR_SIMD_INLINE vbool<4> operator!=(vfloat<4> a, vfloat<4> b) { return vbool<4>(_mm_cmpneq_ps(a.v, b.v)); }
CR_SIMD_INLINE vbool<4> IsNaN(vfloat<4> a) { return vbool<4>(_mm_cmpunord_ps(a.v, a.v)); }
// m ? a : b, lane by lane.
CR_SIMD_INLINE vfloat<4> Select(vbool<4> m, vfloat<4> a, vfloat<4> b)
{
  return vfloat<4>(_mm_blendv_ps(b.v, a.v, m.m));
}
// minps/maxps: a < b ? a : b (a > b ? a : b); a NaN operand yields b.
CR_SIMD_INLINE vfloat<4> Min(vfloat<4> a, vfloat<4> b) { return vfloat<4>(_mm_min_ps(a.v, b.v)); }
CR_SIMD_INLINE vfloat<4> Max(vfloat<4> a, vfloat<4> b) { return vfloat<4>(_mm_max_ps(a.v, b.v)); }
// C's fminf/fmaxf (glibc x86-64: minss/maxss, the other operand when one is NaN).
CR_SIMD_INLINE vfloat<4> FMin(vfloat<4> a, vfloat<4> b) { return Select(IsNaN(b), a, Min(a, b)); }
CR_SIMD_INLINE vfloat<4> FMax(vfloat<4> a, vfloat<4> b) { return Select(IsNaN(b), a, Max(a, b)); }
CR_SIMD_INLINE vfloat<4> Abs(vfloat<4> a) { return vfloat<4>(_mm_andnot_ps(_mm_set1_ps(-0.0f), a.v)); }
// copysign(mag, sgn).
CR_SIMD_INLINE vfloat<4> CopySign(vfloat<4> mag, vfloat<4> sgn)
{
  const __m128 s = _mm_set1_ps(-0.0f);
  return vfloat<4>(_mm_or_ps(_mm_andnot_ps(s, mag.v), _mm_and_ps(s, sgn.v)));
}
CR_SIMD_INLINE vfloat<4> Sqrt(vfloat<4> a) { return vfloat<4>(_mm_sqrt_ps(a.v)); }
// a b - p exactly, for p = a b rounded (Dekker's TwoProduct: Veltkamp's
// split, no FMA on SSE4.1).
CR_SIMD_INLINE vfloat<4> ProductError(vfloat<4> a, vfloat<4> b, vfloat<4> p)
{
  const vfloat<4> ca = vfloat<4>(4097.0f) * a, cb = vfloat<4>(4097.0f) * b;
  const vfloat<4> ah = ca - (ca - a), bh = cb - (cb - b);
  const vfloat<4> al = a - ah, bl = b - bh;
  return ((ah * bh - p) + ah * bl + al * bh) + al * bl;
}
// Smallest lane (no NaN lanes expected: callers mask them to +inf first).
CR_SIMD_INLINE float HMin(vfloat<4> a)
{
  __m128 m = _mm_min_ps(a.v, _mm_shuffle_ps(a.v, a.v, _MM_SHUFFLE(2, 3, 0, 1)));
  m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
  return _mm_cvtss_f32(m);
}

template <>
struct vint<4> {
  __m128i v;
  static constexpr int kSize = 4;
  vint() = default;
  explicit vint(__m128i x) : v(x) {}
  vint(int x) : v(_mm_set1_epi32(x)) {}
  static vint Load(const std::uint32_t* p) { return vint(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))); }
  static vint Lanes() { return vint(_mm_setr_epi32(0, 1, 2, 3)); }
  void Store(std::uint32_t* p) const { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
  std::uint32_t operator[](int i) const
  {
    alignas(16) std::uint32_t a[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(a), v);
    return a[i];
  }
};
CR_SIMD_INLINE vint<4> operator+(vint<4> a, vint<4> b) { return vint<4>(_mm_add_epi32(a.v, b.v)); }
CR_SIMD_INLINE vint<4> operator*(vint<4> a, vint<4> b) { return vint<4>(_mm_mullo_epi32(a.v, b.v)); }
CR_SIMD_INLINE vbool<4> operator==(vint<4> a, vint<4> b)
{
  return vbool<4>(_mm_castsi128_ps(_mm_cmpeq_epi32(a.v, b.v)));
}
// Unsigned a < b.
CR_SIMD_INLINE vbool<4> LessUnsigned(vint<4> a, vint<4> b)
{
  const __m128i eq = _mm_cmpeq_epi32(_mm_min_epu32(a.v, b.v), a.v);  // a <= b
  return AndNot(vbool<4>(_mm_castsi128_ps(eq)), a == b);
}
CR_SIMD_INLINE vint<4> Select(vbool<4> m, vint<4> a, vint<4> b)
{
  return vint<4>(_mm_castps_si128(_mm_blendv_ps(_mm_castsi128_ps(b.v), _mm_castsi128_ps(a.v), m.m)));
}
CR_SIMD_INLINE vint<4> operator-(vint<4> a, vint<4> b) { return vint<4>(_mm_sub_epi32(a.v, b.v)); }
// Signed comparisons.
CR_SIMD_INLINE vbool<4> operator<(vint<4> a, vint<4> b) { return vbool<4>(_mm_castsi128_ps(_mm_cmplt_epi32(a.v, b.v))); }
CR_SIMD_INLINE vbool<4> operator>(vint<4> a, vint<4> b) { return vbool<4>(_mm_castsi128_ps(_mm_cmpgt_epi32(a.v, b.v))); }
// lo = base[idx], hi = base[idx + 1] per lane (idx >= 0): one 8-byte load per lane.
CR_SIMD_INLINE void GatherPairs(const std::uint32_t* base, vint<4> idx, vint<4>& lo, vint<4>& hi)
{
  alignas(16) std::uint32_t i[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(i), idx.v);
  auto pair = [&](int a, int b) {
    const __m128d q = _mm_castsi128_pd(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(base + i[a])));
    return _mm_castpd_ps(_mm_loadh_pd(q, reinterpret_cast<const double*>(base + i[b])));
  };
  const __m128 q0 = pair(0, 1), q1 = pair(2, 3);  // lo hi lo hi
  lo = vint<4>(_mm_castps_si128(_mm_shuffle_ps(q0, q1, _MM_SHUFFLE(2, 0, 2, 0))));
  hi = vint<4>(_mm_castps_si128(_mm_shuffle_ps(q0, q1, _MM_SHUFFLE(3, 1, 3, 1))));
}
// base[idx] lane by lane.
CR_SIMD_INLINE vint<4> Gather(const std::uint32_t* base, vint<4> idx)
{
  alignas(16) std::uint32_t i[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(i), idx.v);
  return vint<4>(_mm_setr_epi32(int(base[i[0]]), int(base[i[1]]), int(base[i[2]]), int(base[i[3]])));
}
// a & b, and a >> n (logical, n < 32), lane by lane.
CR_SIMD_INLINE vint<4> And(vint<4> a, vint<4> b) { return vint<4>(_mm_and_si128(a.v, b.v)); }
CR_SIMD_INLINE vint<4> ShiftRight(vint<4> a, vint<4> n)
{
  alignas(16) std::uint32_t x[4], k[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(x), a.v);
  _mm_store_si128(reinterpret_cast<__m128i*>(k), n.v);
  return vint<4>(_mm_setr_epi32(int(x[0] >> k[0]), int(x[1] >> k[1]), int(x[2] >> k[2]), int(x[3] >> k[3])));
}
// m ? a : 0, lane by lane.
CR_SIMD_INLINE vint<4> MaskedOrZero(vbool<4> m, vint<4> a) { return vint<4>(_mm_and_si128(_mm_castps_si128(m.m), a.v)); }
// (float)i, exact below 2^24 (cell and plane indices).
CR_SIMD_INLINE vfloat<4> ToFloat(vint<4> a) { return vfloat<4>(_mm_cvtepi32_ps(a.v)); }
// (int)floor(x) for x in int range.
CR_SIMD_INLINE vint<4> FloorToInt(vfloat<4> x) { return vint<4>(_mm_cvttps_epi32(_mm_floor_ps(x.v))); }

// Four rows of 8 floats (e.g. RayRecords) transposed: out[j] lane l = rows[l][j].
CR_SIMD_INLINE void LoadTransposed(const float* const rows[4], vfloat<4> out[8])
{
  for (int h = 0; h < 2; ++h) {
    __m128 a = _mm_loadu_ps(rows[0] + 4 * h), b = _mm_loadu_ps(rows[1] + 4 * h);
    __m128 c = _mm_loadu_ps(rows[2] + 4 * h), d = _mm_loadu_ps(rows[3] + 4 * h);
    _MM_TRANSPOSE4_PS(a, b, c, d);
    out[4 * h + 0] = vfloat<4>(a);
    out[4 * h + 1] = vfloat<4>(b);
    out[4 * h + 2] = vfloat<4>(c);
    out[4 * h + 3] = vfloat<4>(d);
  }
}

// Four rows of 4 floats transposed: out[j] lane l = rows[l][j] (gathers four
// 16-byte records, e.g. Sphere, or a vertex row of Triangle, into
// structure-of-arrays form).
CR_SIMD_INLINE void LoadTransposed4(const float* const rows[4], vfloat<4> out[4])
{
  __m128 a = _mm_loadu_ps(rows[0]), b = _mm_loadu_ps(rows[1]);
  __m128 c = _mm_loadu_ps(rows[2]), d = _mm_loadu_ps(rows[3]);
  _MM_TRANSPOSE4_PS(a, b, c, d);
  out[0] = vfloat<4>(a);
  out[1] = vfloat<4>(b);
  out[2] = vfloat<4>(c);
  out[3] = vfloat<4>(d);
}

// Per-lane choice among the x, y, z of one point: ComponentSelector turns a
// lane's axis k (0, 1, 2) into the control PermuteXYZ reads (pshufb bytes
// 4k .. 4k + 3); PermuteXYZ(p, sel) is p[k_lane] in every lane. p must be
// readable for 4 floats (the 16-byte vertex rows of Triangle are).
CR_SIMD_INLINE vint<4> ComponentSelector(vint<4> k)
{
  return vint<4>(_mm_add_epi32(_mm_mullo_epi32(k.v, _mm_set1_epi32(0x04040404)), _mm_set1_epi32(0x03020100)));
}
CR_SIMD_INLINE vfloat<4> PermuteXYZ(const float* p, vint<4> sel)
{
  return vfloat<4>(_mm_castsi128_ps(_mm_shuffle_epi8(_mm_castps_si128(_mm_loadu_ps(p)), sel.v)));
}

// The lanes whose 32 bits (a float's bit pattern, or an integer) have some
// bit of `mask` set, as a lane mask.
CR_SIMD_INLINE unsigned MaskedLanes(__m128i bits, std::uint32_t mask)
{
  const __m128i m = _mm_and_si128(bits, _mm_set1_epi32(static_cast<int>(mask)));
  return unsigned(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(m, _mm_setzero_si128())))) ^ 0xFu;
}
CR_SIMD_INLINE unsigned MaskedLanes(vfloat<4> x, std::uint32_t mask) { return MaskedLanes(_mm_castps_si128(x.v), mask); }
CR_SIMD_INLINE unsigned MaskedLanes(vint<4> x, std::uint32_t mask) { return MaskedLanes(x.v, mask); }

}  // namespace cr::simd::CR_SIMD_NS
