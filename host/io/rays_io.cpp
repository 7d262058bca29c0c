#include "host/io/rays_io.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"

namespace cr {

static_assert(std::endian::native == std::endian::little, "the interchange formats are little-endian");

namespace {

template <typename Record>
std::vector<Record> ReadRecords(const std::string& path, const char (&magic)[8], const char* kind,
                                std::vector<char>* headerOut = nullptr)
{
  const std::size_t size = FileSize(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open");
  char header[16];
  if (size < 16 || !in.read(header, 16))
    throw InputError(path, 0, fmt::format("truncated: {} bytes, a {} file has a 16-byte header", size, kind));
  if (std::memcmp(header, magic, 8) != 0 && !(headerOut && std::memcmp(header, kRaysTimedMagic, 8) == 0))
    throw InputError(path, 0, fmt::format("wrong magic: not a {} file (expected '{}')", kind, std::string(magic, 8)));
  std::uint64_t count = 0;
  std::memcpy(&count, header + 8, 8);
  const std::uint64_t payload = size - 16;
  if (payload % sizeof(Record) != 0 || count != payload / sizeof(Record))
    throw InputError(path, 0,
                     fmt::format("count {} disagrees with the file size ({} bytes hold {} records of {} bytes{})", count,
                                 size, payload / sizeof(Record), sizeof(Record),
                                 payload % sizeof(Record) ? " and a partial one" : ""));
  std::vector<Record> out(static_cast<std::size_t>(count));
  if (count && !in.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(payload)))
    throw InputError(path, 0, "cannot read the records");
  if (headerOut) headerOut->assign(header, header + 16);
  return out;
}

// A CRRAYS02 record: a ray and its time (FORMATS.md extensions).
struct TimedRay {
  RayRecord ray;
  float time;
};
static_assert(sizeof(TimedRay) == 36);

template <typename Record>
void WriteRecords(const std::string& path, const char (&magic)[8], const std::vector<Record>& recs)
{
  WriteAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw RuntimeError(fmt::format("{}: cannot write", path));
    std::uint64_t count = recs.size();
    out.write(magic, 8);
    out.write(reinterpret_cast<const char*>(&count), 8);
    if (!recs.empty())
      out.write(reinterpret_cast<const char*>(recs.data()), static_cast<std::streamsize>(recs.size() * sizeof(Record)));
    out.flush();
    if (!out) throw RuntimeError(fmt::format("{}: write failed (disk full?)", path));
  });
}

}  // namespace

std::string ValidateRay(const RayRecord& r)
{
  const float all[8] = {r.org[0], r.org[1], r.org[2], r.tmin, r.dir[0], r.dir[1], r.dir[2], r.tmax};
  for (float f : all)
    if (std::isnan(f)) return "NaN in the record";
  for (int a = 0; a < 3; ++a) {
    if (std::isinf(r.org[a])) return "infinite origin component";
    if (std::isinf(r.dir[a])) return "infinite direction component";
  }
  if (r.dir[0] == 0.0f && r.dir[1] == 0.0f && r.dir[2] == 0.0f) return "zero direction";
  if (r.tmin < 0.0f) return fmt::format("tmin {} < 0", r.tmin);
  if (std::isinf(r.tmin)) return "infinite tmin";
  if (r.tmin > r.tmax) return fmt::format("tmin {} > tmax {}", r.tmin, r.tmax);
  return {};
}

std::vector<RayRecord> ReadRays(const std::string& path, std::vector<float>* times)
{
  if (times) times->clear();
  // The magic decides the record size: peek at it.
  std::vector<RayRecord> rays;
  char magic[8] = {};
  {
    // A missing or unreadable file: ReadRecords below says what is wrong.
    std::ifstream in(path, std::ios::binary);
    if (in) in.read(magic, 8);
  }
  if (std::memcmp(magic, kRaysTimedMagic, 8) == 0) {
    std::vector<char> header;
    const auto timed = ReadRecords<TimedRay>(path, kRaysTimedMagic, ".rays", &header);
    rays.resize(timed.size());
    bool anyTime = false;
    for (std::size_t i = 0; i < timed.size(); ++i) {
      rays[i] = timed[i].ray;
      const float tau = timed[i].time;
      if (!(tau >= 0.0f && tau <= 1.0f)) throw InputError::Record(path, i, fmt::format("time {} is not in [0, 1]", tau));
      anyTime = anyTime || tau != 0.0f;
    }
    if (times) {
      times->resize(timed.size());
      for (std::size_t i = 0; i < timed.size(); ++i) (*times)[i] = timed[i].time;
    } else if (anyTime) {
      throw InputError(path, 0, "rays with times (CRRAYS02): this use of the file takes CRRAYS01 rays only");
    }
  } else {
    rays = ReadRecords<RayRecord>(path, kRaysMagic, ".rays");
  }
  for (std::size_t i = 0; i < rays.size(); ++i) {
    std::string bad = ValidateRay(rays[i]);
    if (!bad.empty()) throw InputError::Record(path, i, bad);
  }
  return rays;
}

void WriteRays(const std::string& path, const std::vector<RayRecord>& rays, const std::vector<float>& times)
{
  for (std::size_t i = 0; i < rays.size(); ++i) {
    std::string bad = ValidateRay(rays[i]);
    if (!bad.empty()) throw RuntimeError(fmt::format("{}: refusing to write invalid ray {}: {}", path, i, bad));
  }
  if (times.empty()) {
    WriteRecords(path, kRaysMagic, rays);
    return;
  }
  if (times.size() != rays.size())
    throw RuntimeError(fmt::format("{}: {} times for {} rays", path, times.size(), rays.size()));
  std::vector<TimedRay> timed(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!(times[i] >= 0.0f && times[i] <= 1.0f))
      throw RuntimeError(fmt::format("{}: refusing to write ray {} with time {} outside [0, 1]", path, i, times[i]));
    timed[i] = TimedRay{rays[i], times[i]};
  }
  WriteRecords(path, kRaysTimedMagic, timed);
}

std::vector<HitRecord> ReadHits(const std::string& path)
{
  auto hits = ReadRecords<HitRecord>(path, kHitsMagic, ".hits");
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const HitRecord& h = hits[i];
    if (std::isnan(h.t) || std::isnan(h.u) || std::isnan(h.v)) throw InputError::Record(path, i, "NaN in the record");
    if (h.prim == CR_NO_HIT && !std::isinf(h.t))
      throw InputError::Record(path, i, fmt::format("miss (prim 0xFFFFFFFF) with finite t {}", h.t));
    if (h.prim != CR_NO_HIT && std::isinf(h.t))
      throw InputError::Record(path, i, fmt::format("hit of prim {} with infinite t", h.prim));
    if (h.prim != CR_NO_HIT && h.t < 0.0f) throw InputError::Record(path, i, fmt::format("negative t {}", h.t));
  }
  return hits;
}

void WriteHits(const std::string& path, const std::vector<HitRecord>& hits) { WriteRecords(path, kHitsMagic, hits); }

}  // namespace cr
