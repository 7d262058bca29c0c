// Readers and writers of the .rays and .hits interchange formats, exactly as
// ../shared/FORMATS.md fixes them (little-endian; 16-byte header; 32-byte ray
// records, 16-byte hit records). The record structs are those of
// kernels/types.h, so a file's payload is the device buffer as is.
#pragma once

#include <string>
#include <vector>

#include "kernels/types.h"

namespace cr {

inline constexpr char kRaysMagic[8] = {'C', 'R', 'R', 'A', 'Y', 'S', '0', '1'};
// Rays with a time (motion blur, FORMATS.md extensions): 36-byte records, the
// ray and its time in [0, 1].
inline constexpr char kRaysTimedMagic[8] = {'C', 'R', 'R', 'A', 'Y', 'S', '0', '2'};
inline constexpr char kHitsMagic[8] = {'C', 'R', 'H', 'I', 'T', 'S', '0', '1'};

// Reads and validates a ray set; InputError names the file and the record
// index for: wrong magic, count that disagrees with the size, NaN anywhere,
// infinite origin or direction, zero direction, tmin < 0 or infinite,
// tmin > tmax; and for CRRAYS02, a time outside [0, 1]. A CRRAYS02 file's
// times go to `times` (left empty for CRRAYS01: every ray at time 0); with
// times null, a CRRAYS02 file whose times are not all 0 is an InputError.
std::vector<RayRecord> ReadRays(const std::string& path, std::vector<float>* times = nullptr);
// Validates one record (the rules above); returns an empty string when valid.
std::string ValidateRay(const RayRecord& r);
// Writes CRRAYS01, or CRRAYS02 when times (one per ray) are given.
void WriteRays(const std::string& path, const std::vector<RayRecord>& rays,
               const std::vector<float>& times = std::vector<float>());

// Reads a hit set; checks magic, count and that no field is NaN.
std::vector<HitRecord> ReadHits(const std::string& path);
void WriteHits(const std::string& path, const std::vector<HitRecord>& hits);

}  // namespace cr
