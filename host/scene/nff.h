// What an NFF statement reader (nff.cpp) hands a primitive type's ParseNff
// (host/prims/prim_host.h): the statement's keyword, where it is, and its
// numbers, each read with the message a malformed one gets.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "host/scene/scene.h"

namespace cr {

class NffStatement {
 public:
  NffStatement(std::string_view kw, const std::string& f, long l, std::uint32_t m)
      : keyword(kw), file(f), line(l), material(m)
  {
  }
  virtual ~NffStatement() = default;

  std::string_view keyword;  // "s", "c", "p", ...
  const std::string& file;   // for messages
  long line;                 // where the statement starts
  std::uint32_t material;    // the current `f`

  // The next number of the statement; `what` names it in the error for a
  // missing or malformed one (InputError, file:line).
  virtual double Number(const char* what) = 0;
  virtual long Integer(const char* what) = 0;
  glm::dvec3 Vec(const char* what)
  {
    const double x = Number(what), y = Number(what), z = Number(what);
    return {x, y, z};
  }
  // The next word of the statement (a block's operation names, kernels'
  // sdf.h), and the line of the last token read (where a block's error is).
  virtual std::string Word(const char* what) = 0;
  virtual long TokenLine() const { return line; }
  [[noreturn]] virtual void Fail(const std::string& what) = 0;
  [[noreturn]] virtual void FailAt(long at, const std::string& what) = 0;
  // The statement `kw` (at line `at`, with material m) that follows in the
  // same text: a block's operands (a CSG block's leaves and `f` lines).
  virtual std::unique_ptr<NffStatement> Next(std::string_view kw, long at, std::uint32_t m)
  {
    (void)kw;
    (void)m;
    FailAt(at, "a generated statement holds no other statement");
    return nullptr;
  }
  // A PrimInfo for a one-piece statement of type k at this line.
  PrimInfo Info(std::uint32_t k) const
  {
    PrimInfo info;
    info.kind = PrimKind::kShape;
    info.type = static_cast<std::uint8_t>(k);
    info.material = material;
    info.line = static_cast<std::uint32_t>(line);
    return info;
  }
};

// A statement given as its numbers (generated scenes): the same reading,
// checks and warnings as the statement in a file.
class NffValues final : public NffStatement {
 public:
  NffValues(std::string_view kw, const std::string& f, long l, std::vector<double> values, std::uint32_t m = 0)
      : NffStatement(kw, f, l, m), values_(std::move(values))
  {
  }
  double Number(const char* what) override
  {
    if (next_ >= values_.size()) Fail(std::string("missing ") + what);
    return values_[next_++];
  }
  long Integer(const char* what) override { return static_cast<long>(Number(what)); }
  std::string Word(const char* what) override { Fail(std::string("a generated statement has no word for ") + what); }
  [[noreturn]] void Fail(const std::string& what) override;
  [[noreturn]] void FailAt(long, const std::string& what) override { Fail(what); }

 private:
  std::vector<double> values_;
  std::size_t next_ = 0;
};

// Reads the numbers of an `f` statement (colour, Kd, Ks, Phong exponent,
// T, index of refraction) and adds the material; returns its index.
std::uint32_t ReadMaterial(NffStatement& st, Scene& scene);

// Reads a geometry statement with the ParseNff of the type it belongs to
// (host/prims/); false if no type knows its keyword.
bool ReadGeometry(NffStatement& st, Scene& scene);

}  // namespace cr
