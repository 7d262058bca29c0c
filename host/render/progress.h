// A one-line progress bar on stderr for long work: shown only when stderr is
// a terminal and the work has run for more than a second; reports rays/s.
#pragma once

#include <chrono>
#include <cstdint>

namespace cr {

class Progress {
 public:
  Progress(std::uint64_t total, bool enabled);
  void Update(std::uint64_t done, std::uint64_t rays, bool force = false);
  void Finish(std::uint64_t rays);

 private:
  std::uint64_t total_;
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace cr
