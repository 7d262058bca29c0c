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
  f.width = width;
  f.height = height;
  return f;
}

RayRecord PrimaryRay(const CameraFrame& f, double px, double py)
{
  // One pixel step in screen units: the outer row centres are at +-tanHalf.
  const double span = f.height > 1 ? double(f.height - 1) : 1.0;
  const double x = (2.0 * px - double(f.width - 1)) / span * f.tanHalf;
  const double y = (double(f.height - 1) - 2.0 * py) / span * f.tanHalf;
  glm::dvec3 d = f.forward + x * f.right + y * f.up;
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
