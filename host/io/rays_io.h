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
inline constexpr char kHitsMagic[8] = {'C', 'R', 'H', 'I', 'T', 'S', '0', '1'};

// Reads and validates a ray set; InputError names the file and the record
// index for: wrong magic, count that disagrees with the size, NaN anywhere,
// infinite origin or direction, zero direction, tmin < 0 or infinite,
// tmin > tmax.
std::vector<RayRecord> ReadRays(const std::string& path);
// Validates one record (the rules above); returns an empty string when valid.
std::string ValidateRay(const RayRecord& r);
void WriteRays(const std::string& path, const std::vector<RayRecord>& rays);

// Reads a hit set; checks magic, count and that no field is NaN.
std::vector<HitRecord> ReadHits(const std::string& path);
void WriteHits(const std::string& path, const std::vector<HitRecord>& hits);

}  // namespace cr
