// The .rays/.hits formats (round trip, every rejection rule) and `check`
// (self-agreement; every corrupted answer is reported).
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "tests/test_util.h"

using namespace cr;
namespace fs = std::filesystem;
using cr::test::TempPath;

namespace {


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

TEST_CASE("check: the reference agrees with itself, and every corrupted answer is reported")
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
  CHECK(r.agree + r.ties + r.flips + r.wrong == rays.size());
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
  // A shadow ray that only grazes its occluder (within the tolerance) is a
  // flip when reported free, never a tie; all others must be wrong.
  auto oc = ref::CheckHits(ref, shadow, occ, true);
  CHECK(oc.ties == 0);
  CHECK(oc.wrong + oc.flips == blocked);
  CHECK(oc.wrong >= blocked - blocked / 50);
}

TEST_CASE("check: the tolerance belongs to the ray and its hit, not to the primitive, and flips are never agreement")
{
  // A ground sphere of radius 1e6 (top at y = 0) and a unit sphere on it.
  Scene scene;
  ParseNFF("v\nfrom 0 20 40\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 8 8\n"
           "f 1 1 1 1 0 0 0 0\ns 0 -1000000 0 1000000\ns 0 1 0 1\n",
           "ground", scene);
  const ref::ReferenceTracer tr(scene);
  auto verdict = [&](const RayRecord& ray, const HitRecord& hit, bool occlusion) {
    std::vector<ref::RefHit> scratch;
    double rel = 0.0;
    return ref::Adjudicate(tr, ray, hit, occlusion, &rel, scratch);
  };
  // Down at the ground 13 units from the camera's foot.
  const RayRecord down{{0.0f, 20.0f, 40.0f}, 0.0f, {5.0f, -20.0f, -28.0f}, INFINITY};
  const ref::RefHit h = tr.Intersect(ref::MakeRay(down));
  REQUIRE(h.Found());
  REQUIRE(scene.IdOfUnified(h.g) == 0u);
  const double t = h.t;
  // 1e-6 relative is within 2^-16 (|o| + t |d|); 1e-4 is not, although the
  // old tolerance (2^-19 of the primitive's 2e6) allowed 3.8 units.
  CHECK(verdict(down, HitRecord{float(t * (1.0 + 1e-6)), 0u, 0, 0}, false) == ref::Verdict::Agree);
  CHECK(ref::IsWrong(verdict(down, HitRecord{float(t * (1.0 + 1e-4)), 0u, 0, 0}, false)));
  CHECK(ref::IsWrong(verdict(down, HitRecord{float(t * (1.0 - 1e-4)), 0u, 0, 0}, false)));
  CHECK(ref::CheckDelta(40.0, 28.0, t) == doctest::Approx(0x1p-16 * (40.0 + 28.0 * t)));
  // The relative t error of a hit at about t = 0 (a ray from the ground
  // meeting it again, t_ref 1e-12 reported as 0): relative to what the ray
  // resolves (2^-24 |o|inf / |d|inf = 6e-8 here, so 1.7e-5), not to t_ref
  // (1.0).
  {
    Scene flat;
    ParseNFF("f 1 1 1 1 0 0 0 0\np 4\n-5 0 -5\n-5 0 5\n5 0 5\n5 0 -5\n", "flat", flat);
    const ref::ReferenceTracer ft(flat);
    const RayRecord graze{{1.0f, 1e-12f, 0.0f}, 0.0f, {0.0f, -1.0f, 0.0f}, INFINITY};
    std::vector<ref::RefHit> scratch;
    double rel = -1.0;
    CHECK(ref::Adjudicate(ft, graze, HitRecord{0.0f, 0u, 0, 0}, false, &rel, scratch) == ref::Verdict::Agree);
    CHECK(rel > 0.0);
    CHECK(rel < 1e-4);
  }

  // Exactly tangent to the top of the unit sphere, the ground far below:
  // the reference hits (a double root); a reported miss is a flip, counted
  // apart, never agreement or a tie.
  const RayRecord tangent{{-5.0f, 2.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, 10.0f};
  REQUIRE(tr.Intersect(ref::MakeRay(tangent)).Found());
  const HitRecord miss{INFINITY, CR_NO_HIT, 0, 0};
  CHECK(verdict(tangent, miss, false) == ref::Verdict::Flip);
  CHECK(verdict(tangent, miss, true) == ref::Verdict::Flip);
  // Through the unit sphere's centre: a miss is wrong, in both queries.
  const RayRecord through{{-5.0f, 1.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, 10.0f};
  CHECK(verdict(through, miss, false) == ref::Verdict::WrongMissed);
  CHECK(verdict(through, miss, true) == ref::Verdict::WrongMissed);
  // Passing 1e-7 above the tangent (a miss for the reference): a reported
  // hit there is a flip; 0.01 above it, wrong.
  const RayRecord above{{-5.0f, 2.0000002f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, 10.0f};
  REQUIRE(!tr.Intersect(ref::MakeRay(above)).Found());
  CHECK(verdict(above, HitRecord{5.0f, 1u, 0, 0}, false) == ref::Verdict::Flip);
  CHECK(verdict(above, HitRecord{0.0f, 1u, 0, 0}, true) == ref::Verdict::Flip);
  const RayRecord clear{{-5.0f, 2.01f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, 10.0f};
  CHECK(ref::IsWrong(verdict(clear, HitRecord{5.0f, 1u, 0, 0}, false)));
  CHECK(ref::IsWrong(verdict(clear, HitRecord{0.0f, 1u, 0, 0}, true)));

  // CheckHits counts flips apart and sums every verdict to the ray count.
  const std::vector<RayRecord> rays = {down, tangent, through, above};
  const std::vector<HitRecord> hits = {HitRecord{float(t), 0u, 0, 0}, miss, miss, HitRecord{5.0f, 1u, 0, 0}};
  const ref::CheckResult r = ref::CheckHits(tr, rays, hits, false);
  CHECK(r.agree == 1);
  CHECK(r.flips == 2);
  CHECK(r.wrong == 1);
  CHECK(r.ties == 0);
}
