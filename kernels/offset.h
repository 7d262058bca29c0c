/* Robust secondary-ray origins (Waechter & Binder, "A Fast and Robust Method
 * for Avoiding Self-Intersection", Ray Tracing Gems ch. 6): move the hit point
 * off the surface by a number of float ulps proportional to the normal, which
 * scales with the magnitude of the coordinates; near the origin, where ulps
 * vanish, by a small absolute amount. n must be unit length and point to the
 * side the new ray leaves to. */
#ifndef CELLRAY_KERNELS_OFFSET_H
#define CELLRAY_KERNELS_OFFSET_H
#include "prelude.h"

CR_NS_BEGIN

CR_FUNC float Offset_Component(float p, float n)
{
  const float kOrigin = 1.0f / 32.0f;
  const float kFloatScale = 1.0f / 65536.0f;
  const float kIntScale = 256.0f;
  int ofi = (int)(kIntScale * n);
  uint bits = cr_float_bits(p);
  /* Adding to the magnitude bits moves away from zero; subtract for p < 0. */
  int step = (p < 0.0f) ? -ofi : ofi;
  float pi = cr_bits_float(bits + (uint)step); /* modular: no signed overflow */
  return fabs(p) < kOrigin ? p + kFloatScale * n : pi;
}

CR_FUNC void Offset_RayOrigin(const float p[3], const float n[3], float out[3])
{
  for (int a = 0; a < 3; ++a) out[a] = Offset_Component(p[a], n[a]);
}

CR_NS_END

#endif /* CELLRAY_KERNELS_OFFSET_H */
