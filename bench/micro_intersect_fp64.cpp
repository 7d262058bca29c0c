// The intersector micro benchmarks in fp64 mode, and the fp64 hit counts
// every mode is validated against: bench/micro_intersect.inc.
#define CR_MICRO_NS micro_fp64
#define CR_FP64 1
#include "bench/micro_intersect.inc"

namespace cr::micro {
int MicroFp64Hits(Shape shape, const std::vector<RayRecord>& rays) { return micro_fp64::CountHits(shape, rays); }
}  // namespace cr::micro

namespace cr::micro_fp64 {
namespace {
const int kRegistered = [] {
  Register("Sphere_Fp64", Shape::Sphere);
  Register("Triangle_WatertightFp64", Shape::Triangle);
  Register("Cone_Fp64", Shape::Cone);
  return 0;
}();
}  // namespace
}  // namespace cr::micro_fp64
