// The intersector micro benchmarks in robust mode (watertight triangles,
// Woop et al. 2013; the stable quadratic): bench/micro_intersect.inc.
#define CR_MICRO_NS micro_robust
#include "bench/micro_intersect.inc"

namespace cr::micro_robust {
namespace {
const int kRegistered = [] {
  Register("Sphere_Robust", Shape::Sphere);
  Register("Triangle_Watertight", Shape::Triangle);
  Register("Cone_Robust", Shape::Cone);
  Register("Box_Robust", Shape::Box);
  Register("Sphere_Robust", Shape::Sphere, true);
  Register("Triangle_Watertight", Shape::Triangle, true);
  Register("Cone_Robust", Shape::Cone, true);
  return 0;
}();
}  // namespace
}  // namespace cr::micro_robust
