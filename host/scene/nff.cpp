// NFF (Neutral File Format, Eric Haines) reader: v, b, l, f, # here, and the
// geometry statements (s, c, p, pp) in their types' files (host/prims/).
// Statements are read as a token stream (so `c` may span one or two lines),
// except the optional colour of `l`, which must be on the light's line.
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/core/file_util.h"
#include "host/prims/prim_host.h"
#include "host/scene/nff.h"
#include "host/scene/scene.h"

namespace cr {

namespace {

struct Token {
  std::string_view text;
  long line = 0;
};

class Lexer {
 public:
  Lexer(std::string_view text, const std::string& name) : text_(text), name_(name) {}

  // Next token, or nullopt at the end of the text.
  std::optional<Token> Next()
  {
    SkipSpace();
    if (pos_ >= text_.size()) return std::nullopt;
    std::size_t b = pos_;
    while (pos_ < text_.size() && !IsSpace(text_[pos_]) && text_[pos_] != '#') ++pos_;
    lastTokenLine_ = line_;
    return Token{text_.substr(b, pos_ - b), line_};
  }
  // True when another token follows on the current line.
  bool MoreOnLine()
  {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\r')) ++pos_;
    return pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '#';
  }
  long Line() const { return line_; }
  // Line of the last token read: where an unexpected end of file is reported.
  long EofLine() const { return lastTokenLine_; }
  const std::string& Name() const { return name_; }

  [[noreturn]] void Fail(long line, const std::string& what) const { throw InputError(name_, line, what); }

  // Reads one number belonging to `stmt` (started at stmtLine); `what` names it.
  double Number(const char* stmt, long stmtLine, const char* what)
  {
    auto tok = Next();
    if (!tok)
      Fail(EofLine(), fmt::format("truncated '{}' statement (started on line {}): end of file where {} was expected", stmt,
                               stmtLine, what));
    return ParseNumber(*tok, stmt, what);
  }

  double ParseNumber(const Token& tok, const char* stmt, const char* what) const
  {
    std::string_view s = tok.text;
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    double v = 0.0;
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec == std::errc::result_out_of_range)
      Fail(tok.line, fmt::format("'{}': {} '{}' is out of range", stmt, what, tok.text));
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty())
      Fail(tok.line, fmt::format("'{}': expected a number for {}, got '{}'", stmt, what, tok.text));
    if (!std::isfinite(v)) Fail(tok.line, fmt::format("'{}': {} is not a finite number: '{}'", stmt, what, tok.text));
    if (std::fabs(v) > double(std::numeric_limits<float>::max()))
      Fail(tok.line, fmt::format("'{}': {} '{}' does not fit in a float", stmt, what, tok.text));
    return v;
  }

  long Integer(const char* stmt, long stmtLine, const char* what)
  {
    auto tok = Next();
    if (!tok)
      Fail(EofLine(), fmt::format("truncated '{}' statement (started on line {}): end of file where {} was expected", stmt,
                               stmtLine, what));
    long v = 0;
    auto [ptr, ec] = std::from_chars(tok->text.data(), tok->text.data() + tok->text.size(), v);
    if (ec != std::errc() || ptr != tok->text.data() + tok->text.size())
      Fail(tok->line, fmt::format("'{}': expected an integer for {}, got '{}'", stmt, what, tok->text));
    return v;
  }

  void Keyword(const char* expected, long stmtLine)
  {
    auto tok = Next();
    if (!tok)
      Fail(EofLine(), fmt::format("truncated 'v' block (started on line {}): end of file where '{}' was expected", stmtLine,
                               expected));
    if (tok->text != expected)
      Fail(tok->line, fmt::format("'v' block: expected '{}', got '{}'", expected, tok->text));
  }

 private:
  static bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }
  void SkipSpace()
  {
    while (pos_ < text_.size()) {
      char c = text_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (IsSpace(c)) {
        ++pos_;
      } else if (c == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
  }

  std::string_view text_;
  std::string name_;
  std::size_t pos_ = 0;
  long line_ = 1;
  long lastTokenLine_ = 1;
};

glm::dvec3 Vec(Lexer& lx, const char* stmt, long line, const char* what)
{
  double x = lx.Number(stmt, line, what);
  double y = lx.Number(stmt, line, what);
  double z = lx.Number(stmt, line, what);
  return {x, y, z};
}

glm::vec3 F(const glm::dvec3& v) { return glm::vec3(v); }

// A geometry statement as its type's ParseNff reads it.
class LexerStatement final : public NffStatement {
 public:
  LexerStatement(Lexer& lx, std::string_view kw, long stmtLine, std::uint32_t stmtMaterial)
      : NffStatement(kw, lx.Name(), stmtLine, stmtMaterial), lx_(lx), stmt_(kw)
  {
  }
  double Number(const char* what) override { return lx_.Number(stmt_.c_str(), line, what); }
  long Integer(const char* what) override { return lx_.Integer(stmt_.c_str(), line, what); }
  std::string Word(const char* what) override
  {
    auto tok = lx_.Next();
    if (!tok)
      lx_.Fail(lx_.EofLine(), fmt::format("truncated '{}' block (started on line {}): end of file where {} was expected",
                                          stmt_, line, what));
    return std::string(tok->text);
  }
  long TokenLine() const override { return lx_.EofLine(); }
  std::unique_ptr<NffStatement> Next(std::string_view kw, long at, std::uint32_t m) override
  {
    return std::make_unique<LexerStatement>(lx_, kw, at, m);
  }
  [[noreturn]] void Fail(const std::string& what) override { lx_.Fail(line, what); }
  [[noreturn]] void FailAt(long at, const std::string& what) override { lx_.Fail(at, what); }

 private:
  Lexer& lx_;
  std::string stmt_;
};

}  // namespace

void NffValues::Fail(const std::string& what) { throw InputError(file, line, what); }

std::uint32_t ReadMaterial(NffStatement& st, Scene& scene)
{
  Material m;
  m.color = F(st.Vec("a colour component"));
  m.kd = float(st.Number("Kd"));
  m.ks = float(st.Number("Ks"));
  m.shine = float(st.Number("the Phong exponent"));
  m.transmittance = float(st.Number("the transmittance T"));
  m.ior = float(st.Number("the index of refraction"));
  if (m.ior < 0.0f) st.Fail(fmt::format("'f': index of refraction {} is negative", m.ior));
  scene.materials.push_back(m);
  return static_cast<std::uint32_t>(scene.materials.size() - 1);
}

bool ReadGeometry(NffStatement& st, Scene& scene)
{
  bool read = false;
#define CR_NFF_PARSE_(T, U, a) read = read || ParseNff(PrimTag<T>{}, st, scene);
  CR_PRIM_TYPES(CR_NFF_PARSE_)
#undef CR_NFF_PARSE_
  return read;
}

void ParseNFF(std::string_view text, const std::string& name, Scene& scene, bool viewOnly)
{
  Lexer lx(text, name);
  if (scene.materials.empty()) scene.materials.push_back(Material{});
  std::uint32_t material = 0;
  glm::vec3 motion(0.0f);  // the current `motion`
  bool anyStatement = false;
  while (auto tok = lx.Next()) {
    const long line = tok->line;
    const std::string_view kw = tok->text;
    anyStatement = true;
    if (viewOnly && kw != "v" && kw != "b" && kw != "l" && kw != "lens")
      lx.Fail(line, fmt::format("'{}' statement in a view file (only v, lens, b, l and comments belong there)", kw));
    if (kw == "v") {
      Camera cam;
      lx.Keyword("from", line);
      cam.from = F(Vec(lx, "v", line, "a 'from' coordinate"));
      lx.Keyword("at", line);
      cam.at = F(Vec(lx, "v", line, "an 'at' coordinate"));
      lx.Keyword("up", line);
      cam.up = F(Vec(lx, "v", line, "an 'up' coordinate"));
      lx.Keyword("angle", line);
      cam.angle = float(lx.Number("v", line, "the angle"));
      lx.Keyword("hither", line);
      cam.hither = float(lx.Number("v", line, "the hither distance"));
      lx.Keyword("resolution", line);
      long w = lx.Integer("v", line, "the x resolution");
      long h = lx.Integer("v", line, "the y resolution");
      if (!(cam.angle > 0.0f && cam.angle < 180.0f))
        lx.Fail(line, fmt::format("'v': angle {} is not in (0, 180) degrees", cam.angle));
      if (cam.hither < 0.0f) lx.Fail(line, fmt::format("'v': hither {} is negative", cam.hither));
      if (w < 1 || h < 1 || w > 65536 || h > 65536)
        lx.Fail(line, fmt::format("'v': resolution {} x {} is not in 1..65536", w, h));
      glm::dvec3 fwd = glm::dvec3(cam.at) - glm::dvec3(cam.from);
      if (glm::length(fwd) == 0.0) lx.Fail(line, "'v': 'from' and 'at' are the same point");
      if (glm::length(glm::cross(fwd, glm::dvec3(cam.up))) == 0.0)
        lx.Fail(line, "'v': 'up' is zero or parallel to the view direction");
      cam.width = int(w);
      cam.height = int(h);
      scene.camera = cam;
      scene.hasCamera = true;
    } else if (kw == "lens") {
      if (!scene.hasCamera) lx.Fail(line, "'lens' before the 'v' block it belongs to");
      const double a = lx.Number("lens", line, "the aperture radius");
      const double f = lx.Number("lens", line, "the focal distance");
      if (!(a >= 0.0) || !std::isfinite(a)) lx.Fail(line, fmt::format("'lens': aperture radius {} is negative", a));
      if (!(f > 0.0) || !std::isfinite(f)) lx.Fail(line, fmt::format("'lens': focal distance {} is not > 0", f));
      scene.camera.aperture = float(a);
      scene.camera.focal = float(f);
    } else if (kw == "motion") {
      const glm::dvec3 m = Vec(lx, "motion", line, "a displacement component");
      if (!std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.z))
        lx.Fail(line, "'motion': the displacement is not finite");
      motion = F(m);
    } else if (kw == "b") {
      scene.background = F(Vec(lx, "b", line, "a background colour component"));
    } else if (kw == "l") {
      Light l;
      l.position = F(Vec(lx, "l", line, "a light coordinate"));
      if (lx.MoreOnLine()) l.color = F(Vec(lx, "l", line, "a light colour component"));
      scene.lights.push_back(l);
    } else if (kw == "f") {
      LexerStatement st(lx, kw, line, material);
      material = ReadMaterial(st, scene);
    } else {
      // Geometry: the statement of some primitive type (host/prims/).
      LexerStatement st(lx, kw, line, material);
      const std::size_t before = scene.prims.size();
      if (ParseAreaLight(st, scene)) {
        if (motion != glm::vec3(0.0f))
          lx.Fail(line, fmt::format("'{}': an area light cannot move (end the motion with 'motion 0 0 0' before it)", kw));
      } else if (!ReadGeometry(st, scene)) {
        lx.Fail(line, fmt::format("unknown statement '{}'", kw));
      }
      if (motion != glm::vec3(0.0f)) {
        for (std::size_t i = before; i < scene.prims.size(); ++i) scene.prims[i].motion = motion;
        scene.hasMotion = true;
      }
    }
  }
  if (!anyStatement) throw InputError(name, 0, viewOnly ? "empty view file" : "empty scene file");
}

Scene LoadNFF(const std::string& path)
{
  std::vector<char> data = ReadFile(path);
  Scene scene;
  scene.path = path;
  ParseNFF(std::string_view(data.data(), data.size()), path, scene, false);
  if (scene.prims.empty()) throw InputError(path, 0, "no geometry: the scene has no s, c, p or pp statement");
  if (!scene.hasCamera) Warn(fmt::format("{}: no 'v' block: using a default camera", path));
  return scene;
}

}  // namespace cr
