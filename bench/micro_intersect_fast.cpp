// The intersector micro benchmarks in fast mode (Moller-Trumbore, the
// textbook quadratic): bench/micro_intersect.inc.
#define CR_MICRO_NS micro_fast
#define CR_FAST 1
#include "bench/micro_intersect.inc"

namespace cr::micro_fast {
namespace {
const int kRegistered = [] {
  Register("Sphere_Fast", Shape::Sphere);
  Register("Triangle_MollerTrumbore", Shape::Triangle);
  Register("Cone_Fast", Shape::Cone);
  Register("Box_Fast", Shape::Box);
  Register("Triangle_MollerTrumbore", Shape::Triangle, true);
  return 0;
}();
}  // namespace
}  // namespace cr::micro_fast
