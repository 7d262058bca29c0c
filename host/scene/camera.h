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
  double aperture = 0.0, focal = 1.0;  // thin lens (Camera::aperture, focal)
  int width = 1, height = 1;
};

CameraFrame MakeCameraFrame(const Camera& cam, int width, int height);

// Ray through continuous pixel position (px, py): (0, 0) is the centre of the
// top-left pixel, (width - 1, height - 1) of the bottom-right one. SPD corner
// rays use px, py in -0.5, 0.5, ..., width - 0.5.
RayRecord PrimaryRay(const CameraFrame& f, double px, double py);

// The thin-lens ray through (px, py) from lens sample (s1, s2) in [0, 1)^2:
// from the point of the aperture disc (radius f.aperture, in the plane of
// right and up through the eye; concentric mapping) to where the pinhole ray
// meets the focal plane (distance f.focal along forward), its direction
// scaled so that its forward component is 1 (t = hither is still the hither
// plane). With aperture 0 it is PrimaryRay exactly.
RayRecord LensRay(const CameraFrame& f, double px, double py, double s1, double s2);

// Shirley and Chiu's concentric map of [0, 1)^2 onto the unit disc.
glm::dvec2 ConcentricDisc(double s1, double s2);

}  // namespace cr
