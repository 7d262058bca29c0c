// Pinhole camera of an NFF `v` block. The view angle spans the centres of the
// outer pixel rows (NFF's convention); pixels are square. Primary directions
// are not normalised: d = forward + x right + y up with |forward| = 1, so that
// t = hither is exactly the hither plane.
#pragma once

#include <glm/glm.hpp>

#include "kernels/types.h"
#include "host/scene/scene.h"

namespace cr {

struct CameraFrame {
  glm::dvec3 eye, forward, right, up;
  double tanHalf = 1.0;
  double hither = 0.0;
  int width = 1, height = 1;
};

CameraFrame MakeCameraFrame(const Camera& cam, int width, int height);

// Ray through continuous pixel position (px, py): (0, 0) is the centre of the
// top-left pixel, (width - 1, height - 1) of the bottom-right one. SPD corner
// rays use px, py in -0.5, 0.5, ..., width - 0.5.
RayRecord PrimaryRay(const CameraFrame& f, double px, double py);

}  // namespace cr
