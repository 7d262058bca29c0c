// Conformance: every structure on every CPU backend against the fp64
// reference, on every SPD scene and ray kind, at a reduced ray count
// (the full-size run is bench/conformance.sh).
#include "tests/test_util.h"

using namespace cr;

namespace {

void RunConformance(Backend backend, Precision precision, int size)
{
  for (const std::string& name : test::SpdScenes())
    test::CheckConformance(test::CachedScene(test::SpdPath(name)), name, backend, precision, size);
}

}  // namespace

TEST_CASE("conformance: scalar robust, every SPD scene x structure x ray kind")
{
  RunConformance(Backend::Scalar, Precision::Robust, 48);
}

TEST_CASE("conformance: scalar fp64, every SPD scene x structure x ray kind")
{
  RunConformance(Backend::Scalar, Precision::Fp64, 32);
}
