// The .rays/.hits formats (round trip, every rejection rule) and `check`
// (self-agreement; every corrupted answer is reported).
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "core/error.h"
#include "core/file_util.h"
#include "test_util.h"

using namespace cr;
namespace fs = std::filesystem;

namespace {

std::string TempPath(const std::string& name)
{
  fs::path dir = fs::temp_directory_path() / ("cellray_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return (dir / name).string();
}

void WriteRaw(const std::string& path, const char* magic, std::uint64_t count, const void* payload, std::size_t bytes)
{
  std::ofstream out(path, std::ios::binary);
  out.write(magic, 8);
  out.write(reinterpret_cast<const char*>(&count), 8);
  out.write(static_cast<const char*>(payload), static_cast<std::streamsize>(bytes));
}

RayRecord GoodRay() { return RayRecord{{0.0f, 0.0f, 0.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY}; }

std::string ReadError(const std::string& path)
{
  try {
    ReadRays(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("rays and hits round trip bit for bit")
{
  std::vector<RayRecord> rays = {GoodRay(), RayRecord{{1.5f, -2.0f, 3.0f}, 0.25f, {-0.0f, 1e-30f, -1.0f}, 7.0f}};
  std::string rp = TempPath("rt.rays");
  WriteRays(rp, rays);
  CHECK(FileSize(rp) == 16 + 32 * rays.size());
  auto back = ReadRays(rp);
  REQUIRE(back.size() == rays.size());
  CHECK(std::memcmp(back.data(), rays.data(), sizeof(RayRecord) * rays.size()) == 0);
  std::vector<char> raw = ReadFile(rp);
  CHECK(std::string(raw.data(), 8) == "CRRAYS01");

  std::vector<HitRecord> hits = {HitRecord{1.0f, 3u, 0.25f, 0.5f}, HitRecord{INFINITY, CR_NO_HIT, 0.0f, 0.0f}};
  std::string hp = TempPath("rt.hits");
  WriteHits(hp, hits);
  auto hb = ReadHits(hp);
  REQUIRE(hb.size() == 2);
  CHECK(std::memcmp(hb.data(), hits.data(), sizeof(HitRecord) * 2) == 0);
  CHECK(std::string(ReadFile(hp).data(), 8) == "CRHITS01");
}

TEST_CASE("rays reader rejects each malformed record with file and record index")
{
  struct Case {
    const char* name;
    RayRecord ray;
    const char* message;
  };
  const float nan = std::nanf("");
  std::vector<Case> cases = {
      {"nan-origin", {{nan, 0, 0}, 0, {0, 0, 1}, 1}, "NaN"},
      {"nan-tmax", {{0, 0, 0}, 0, {0, 0, 1}, nan}, "NaN"},
      {"inf-origin", {{INFINITY, 0, 0}, 0, {0, 0, 1}, 1}, "infinite origin"},
      {"inf-dir", {{0, 0, 0}, 0, {0, -INFINITY, 1}, 1}, "infinite direction"},
      {"zero-dir", {{0, 0, 0}, 0, {0, -0.0f, 0}, 1}, "zero direction"},
      {"neg-tmin", {{0, 0, 0}, -1, {0, 0, 1}, 1}, "tmin -1 < 0"},
      {"tmin-gt-tmax", {{0, 0, 0}, 2, {0, 0, 1}, 1}, "tmin 2 > tmax 1"},
  };
  for (const Case& c : cases) {
    std::vector<RayRecord> rays = {GoodRay(), GoodRay(), c.ray};
    std::string p = TempPath(std::string(c.name) + ".rays");
    WriteRaw(p, "CRRAYS01", rays.size(), rays.data(), sizeof(RayRecord) * rays.size());
    std::string err = ReadError(p);
    INFO(c.name, ": ", err);
    CHECK(err.find(p + ": record 2: ") == 0);
    CHECK(err.find(c.message) != std::string::npos);
  }
  SUBCASE("count disagrees with size")
  {
    std::vector<RayRecord> rays = {GoodRay(), GoodRay()};
    std::string p = TempPath("count.rays");
    WriteRaw(p, "CRRAYS01", 3, rays.data(), sizeof(RayRecord) * 2);
    CHECK(ReadError(p).find("count 3 disagrees with the file size") != std::string::npos);
    WriteRaw(p, "CRRAYS01", 1, rays.data(), sizeof(RayRecord) + 5);
    CHECK(ReadError(p).find("partial") != std::string::npos);
  }
  SUBCASE("wrong magic, truncated header, empty, missing")
  {
    std::string p = TempPath("magic.rays");
    WriteRaw(p, "CRHITS01", 0, nullptr, 0);
    CHECK(ReadError(p).find("wrong magic") != std::string::npos);
    std::ofstream(TempPath("empty.rays"), std::ios::binary).close();
    CHECK(ReadError(TempPath("empty.rays")).find("truncated") != std::string::npos);
    CHECK(ReadError(TempPath("missing.rays")).find("no such file") != std::string::npos);
  }
}

TEST_CASE("check: the reference agrees with itself; every corrupted answer is reported")
{
  const Scene& scene = test::CachedScene(test::SpdPath("balls"));
  const auto& ref = test::CachedReference(scene);
  auto rays = test::MakeRays(scene, RayKind::Primary, 64);
  TraceConfig cfg;
  cfg.backend = Backend::Reference;
  auto tracer = CreateTracer(scene, cfg);
  std::vector<HitRecord> hits;
  tracer->Trace(rays, hits, false, nullptr);
  auto self = ref::CheckHits(ref, rays, hits, false);
  CHECK(self.wrong == 0);
  CHECK(self.agree == rays.size());

  // Corrupt every 97th answer in one of three ways.
  std::vector<std::uint64_t> corrupted;
  for (std::size_t i = 5; i < hits.size(); i += 97) {
    REQUIRE(hits[i].prim != CR_NO_HIT);  // every balls ray hits
    switch (corrupted.size() % 3) {
      case 0: hits[i].t = hits[i].t * 1.5f + 1.0f; break;  // not on the surface
      case 1: hits[i] = HitRecord{INFINITY, CR_NO_HIT, 0, 0}; break;  // a robust hit dropped
      case 2: hits[i].prim = hits[i].prim == 0 ? 1 : 0; break;        // the wrong primitive
    }
    corrupted.push_back(i);
  }
  auto r = ref::CheckHits(ref, rays, hits, false);
  CHECK(r.wrong == corrupted.size());
  CHECK(r.agree + r.ties + r.wrong == rays.size());
  const std::size_t listed = std::min<std::size_t>(16, corrupted.size());
  CHECK(std::vector<std::uint64_t>(r.firstWrong.begin(), r.firstWrong.end()) ==
        std::vector<std::uint64_t>(corrupted.begin(), corrupted.begin() + listed));

  // Occlusion: "free" for an occluded shadow ray is wrong, and so is an
  // occluder that is not on the ray.
  auto shadow = test::MakeRays(scene, RayKind::Shadow, 32);
  std::vector<HitRecord> occ;
  tracer->Trace(shadow, occ, true, nullptr);
  CHECK(ref::CheckHits(ref, shadow, occ, true).wrong == 0);
  std::size_t blocked = 0;
  for (std::size_t i = 0; i < occ.size(); ++i)
    if (occ[i].prim != CR_NO_HIT) {
      occ[i] = HitRecord{INFINITY, CR_NO_HIT, 0, 0};
      ++blocked;
    }
  REQUIRE(blocked > 0);
  // A shadow ray that only grazes its occluder (within the tolerance) is
  // legitimately a tie when reported free; all others must be wrong.
  auto oc = ref::CheckHits(ref, shadow, occ, true);
  CHECK(oc.wrong + oc.ties == blocked);
  CHECK(oc.wrong >= blocked - blocked / 50);
}
