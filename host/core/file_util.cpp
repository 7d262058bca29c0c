#include "host/core/file_util.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <unistd.h>

#include "host/core/error.h"

namespace cr {

void WriteAtomically(const std::string& path, const std::function<void(const std::string&)>& write)
{
  namespace fs = std::filesystem;
  fs::path target(path);
  // Keep the extension last: image writers pick the format by it.
  std::string tmp = (target.parent_path() / fmt::format(".{}.tmp{}{}", target.stem().string(), ::getpid(),
                                                        target.extension().string()))
                        .string();
  try {
    write(tmp);
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) throw RuntimeError(fmt::format("{}: cannot rename into place: {}", path, ec.message()));
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

void WriteFileAtomically(const std::string& path, const void* data, std::size_t size)
{
  WriteAtomically(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw RuntimeError(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
    std::size_t written = size ? std::fwrite(data, 1, size, f) : 0;
    bool ok = written == size && std::fflush(f) == 0;
    ok = (std::fclose(f) == 0) && ok;
    if (!ok) throw RuntimeError(fmt::format("{}: write failed: {}", path, std::strerror(errno)));
  });
}

std::size_t FileSize(const std::string& path)
{
  namespace fs = std::filesystem;
  std::error_code ec;
  auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw InputError(path, 0, "cannot open: no such file");
  if (!fs::is_regular_file(st)) throw InputError(path, 0, "cannot open: not a regular file");
  auto size = fs::file_size(path, ec);
  if (ec) throw InputError(path, 0, fmt::format("cannot read: {}", ec.message()));
  return static_cast<std::size_t>(size);
}

std::vector<char> ReadFile(const std::string& path)
{
  std::size_t size = FileSize(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  std::vector<char> data(size);
  if (size && !in.read(data.data(), static_cast<std::streamsize>(size)))
    throw InputError(path, 0, "cannot read the whole file");
  return data;
}

}  // namespace cr
