// MPI (host/mpi/): `mpirun -np 2 cellray render` in every distribution mode
// gives the single process's image bit for bit, `trace` the same hits in
// input order; a bad argument ends every rank with one message and no
// output file. Runs only in a build with MPI and where mpirun exists
// (scripts/install-deps.sh installs Open MPI).
#include <cstdlib>
#include <filesystem>

#include <unistd.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/core/file_util.h"
#include "tests/test_util.h"

using namespace cr;
namespace fs = std::filesystem;

#ifdef CELLRAY_HAVE_MPI

namespace {

bool HaveMpirun() { return std::system("command -v mpirun >/dev/null 2>&1") == 0; }

fs::path MpiDir()
{
  return test::ProcessTempDir("cellray_mpi");
}

// Runs cellray with `args` (under mpirun -np n when n > 0); returns the exit code.
int RunMpi(int n, const std::string& args, const fs::path& log)
{
  std::string launcher;
  if (n > 0) {
    // --oversubscribe: more ranks than cores; as root (CI containers) Open MPI
    // asks for --allow-run-as-root.
    launcher = fmt::format("mpirun -np {} --oversubscribe {} --mca btl self,vader ", n,
                           ::geteuid() == 0 ? "--allow-run-as-root" : "");
  }
  const std::string cmd = fmt::format("cd {} && OMPI_MCA_rmaps_base_oversubscribe=1 {}{} {} >{} 2>&1",
                                      test::SourcePath("."), launcher, CELLRAY_BINARY, args, log.string());
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool SameFileBytes(const fs::path& a, const fs::path& b)
{
  return fs::exists(a) && fs::exists(b) && ReadFile(a.string()) == ReadFile(b.string());
}

}  // namespace

TEST_CASE("mpi: render with 2 ranks in tiles, bands and bands-data is bit-identical to one process")
{
  if (!HaveMpirun()) {
    MESSAGE("mpirun not found: skipped");
    return;
  }
  const fs::path d = MpiDir();
  struct Case {
    const char* scene;
    const char* args;
  };
  const Case cases[] = {{"scenes/spd/balls.nff", "--spd --size 64x48 --backend simd"},
                        {"scenes/spd/gears.nff", "--spd --size 48x48 --backend scalar --accel grid"},
                        {"scenes/distributed/cornell.nff", "--integrator path --spp 4 --size 40x40 --backend simd"},
                        {"scenes/distributed/motion.nff", "--integrator path --spp 2 --size 40x24 --backend scalar"}};
  for (const Case& c : cases) {
    const fs::path one = d / "one.exr";
    REQUIRE(RunMpi(0, fmt::format("render {} {} --no-progress -o {}", c.scene, c.args, one.string()), d / "one.log") == 0);
    for (const char* mode : {"tiles", "bands", "bands-data"}) {
      const fs::path two = d / fmt::format("two_{}.exr", mode);
      const int rc = RunMpi(2, fmt::format("render {} {} --distribute {} --tile-rows 3 -o {}", c.scene, c.args, mode, two.string()),
                         d / "two.log");
      const auto log = ReadFile((d / "two.log").string());
      const std::string text(log.begin(), log.end());
      INFO(std::string(c.scene), " ", std::string(mode), ": ", text);
      CHECK(rc == 0);
      CHECK(SameFileBytes(one, two));
      CHECK(text.find("\"ranks\":2") != std::string::npos);
    }
  }
}

TEST_CASE("mpi: bands-data with 4 ranks passes rays between bands and gives the single process's image")
{
  if (!HaveMpirun()) return;
  const fs::path d = MpiDir();
  struct Case {
    const char* scene;
    const char* args;
  };
  // SPD shadows towards lights above (tree: the ground's shadow rays all
  // go up to the tree's band), a thin lens (rays that start off the eye),
  // moving pieces with the path tracer.
  const Case cases[] = {{"scenes/spd/tree.nff", "--spd --size 64x64 --backend simd"},
                        {"scenes/distributed/dof.nff", "--spp 2 --size 48x48 --backend scalar --accel octree"},
                        {"scenes/distributed/motion.nff", "--integrator path --spp 2 --size 48x32 --backend simd --accel grid"}};
  for (const Case& c : cases) {
    const fs::path one = d / "one4.exr", four = d / "four.exr", json = d / "four.json";
    REQUIRE(RunMpi(0, fmt::format("render {} {} --no-progress -o {}", c.scene, c.args, one.string()), d / "one4.log") == 0);
    const int rc = RunMpi(4, fmt::format("render {} {} --distribute bands-data -o {} --stats {}", c.scene, c.args,
                                      four.string(), json.string()),
                       d / "four.log");
    const auto log = ReadFile((d / "four.log").string());
    INFO(std::string(c.scene), ": ", std::string(log.begin(), log.end()));
    CHECK(rc == 0);
    CHECK(SameFileBytes(one, four));
    // Every rank holds part of the scene; rays crossed bands.
    const auto js = ReadFile(json.string());
    const nlohmann::json j = nlohmann::json::parse(std::string(js.begin(), js.end()));
    REQUIRE(j["mpi"]["per_rank"].size() == 4);
    std::uint64_t forwarded = 0, pieces = 0;
    for (const auto& r : j["mpi"]["per_rank"]) {
      forwarded += r["bands_data"]["forwarded"].get<std::uint64_t>();
      pieces += r["bands_data"]["local_pieces"].get<std::uint64_t>();
      CHECK(r["bands_data"]["local_pieces"].get<std::uint64_t>() < r["bands_data"]["total_pieces"].get<std::uint64_t>());
    }
    CHECK(forwarded > 0);
    CHECK(pieces > 0);
  }
}

TEST_CASE("mpi: trace with 2 ranks writes the single process's hits in input order")
{
  if (!HaveMpirun()) return;
  const fs::path d = MpiDir();
  const fs::path rays = d / "m.rays", one = d / "one.hits", two = d / "two.hits";
  REQUIRE(RunMpi(0, fmt::format("rays scenes/distributed/motion.nff --kind diffuse --count 3001 -o {}", rays.string()),
              d / "r.log") == 0);
  REQUIRE(RunMpi(0, fmt::format("trace scenes/distributed/motion.nff --rays {} --backend simd -o {}", rays.string(), one.string()),
              d / "t1.log") == 0);
  CHECK(RunMpi(2, fmt::format("trace scenes/distributed/motion.nff --rays {} --backend simd -o {}", rays.string(), two.string()),
            d / "t2.log") == 0);
  CHECK(SameFileBytes(one, two));
}

TEST_CASE("mpi: a bad argument ends every rank with exit 2 and writes nothing")
{
  if (!HaveMpirun()) return;
  const fs::path d = MpiDir();
  const fs::path out = d / "never.exr";
  const int rc = RunMpi(2, fmt::format("render scenes/spd/balls.nff --spp 0 -o {}", out.string()), d / "bad.log");
  const auto log = ReadFile((d / "bad.log").string());
  const std::string text(log.begin(), log.end());
  INFO(text);
  CHECK(rc == 2);
  CHECK(text.find("cellray: --spp 0 is not in 1..65536") != std::string::npos);
  CHECK_FALSE(fs::exists(out));
}

#endif
