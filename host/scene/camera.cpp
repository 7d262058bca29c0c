#include "host/scene/camera.h"

#include <cmath>

namespace cr {

CameraFrame MakeCameraFrame(const Camera& cam, int width, int height)
{
  CameraFrame f;
  f.eye = glm::dvec3(cam.from);
  f.forward = glm::normalize(glm::dvec3(cam.at) - f.eye);
  f.right = glm::normalize(glm::cross(f.forward, glm::dvec3(cam.up)));
  f.up = glm::cross(f.right, f.forward);
  f.tanHalf = std::tan(0.5 * double(cam.angle) * 3.14159265358979323846 / 180.0);
  f.hither = cam.hither;
  f.aperture = cam.aperture;
  f.focal = cam.focal;
  f.width = width;
  f.height = height;
  return f;
}

namespace {

glm::dvec3 PinholeDir(const CameraFrame& f, double px, double py)
{
  // One pixel step in screen units: the outer row centres are at +-tanHalf.
  const double span = f.height > 1 ? double(f.height - 1) : 1.0;
  const double x = (2.0 * px - double(f.width - 1)) / span * f.tanHalf;
  const double y = (double(f.height - 1) - 2.0 * py) / span * f.tanHalf;
  return f.forward + x * f.right + y * f.up;
}

}  // namespace

glm::dvec2 ConcentricDisc(double s1, double s2)
{
  const double a = 2.0 * s1 - 1.0, b = 2.0 * s2 - 1.0;
  if (a == 0.0 && b == 0.0) return {0.0, 0.0};
  constexpr double kQuarterPi = 0.78539816339744830962;
  double r, phi;
  if (std::fabs(a) > std::fabs(b)) {
    r = a;
    phi = kQuarterPi * (b / a);
  } else {
    r = b;
    phi = 2.0 * kQuarterPi - kQuarterPi * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

RayRecord LensRay(const CameraFrame& f, double px, double py, double s1, double s2)
{
  if (!(f.aperture > 0.0)) return PrimaryRay(f, px, py);
  const glm::dvec3 d = PinholeDir(f, px, py);
  const glm::dvec3 focus = f.eye + f.focal * d;
  const glm::dvec2 disc = f.aperture * ConcentricDisc(s1, s2);
  const glm::dvec3 o = f.eye + disc.x * f.right + disc.y * f.up;
  const glm::dvec3 dir = (focus - o) / f.focal;
  RayRecord r;
  for (int a = 0; a < 3; ++a) {
    r.org[a] = static_cast<float>(o[a]);
    r.dir[a] = static_cast<float>(dir[a]);
  }
  r.tmin = static_cast<float>(f.hither);
  r.tmax = INFINITY;
  return r;
}

RayRecord PrimaryRay(const CameraFrame& f, double px, double py)
{
  const glm::dvec3 d = PinholeDir(f, px, py);
  RayRecord r;
  for (int a = 0; a < 3; ++a) {
    r.org[a] = static_cast<float>(f.eye[a]);
    r.dir[a] = static_cast<float>(d[a]);
  }
  r.tmin = static_cast<float>(f.hither);
  r.tmax = INFINITY;
  return r;
}

}  // namespace cr
