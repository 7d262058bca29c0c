// Bad input at every boundary, through the real binary: exit code 2 and
// `cellray: FILE:LINE: what` for malformed scenes, views, rays and hits and
// for bad command lines; exit 1 for runtime failures; warnings (exit 0) for
// degenerate primitives, whose ids stay stable; never a partial output file.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/test_util.h"

using namespace cr;
namespace fs = std::filesystem;
using cr::test::Slurp;

namespace {

struct Result {
  int code = -1;
  std::string out, err;
};

fs::path BadInputDir()
{
  return test::ProcessTempDir("cellray_bad");
}

std::string Write(const std::string& name, const std::string& text)
{
  fs::path p = BadInputDir() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}


Result Run(const std::string& args)
{
  fs::path out = BadInputDir() / "stdout.txt", err = BadInputDir() / "stderr.txt";
  std::string cmd = std::string(CELLRAY_BINARY) + " " + args + " >" + out.string() + " 2>" + err.string();
  int status = std::system(cmd.c_str());
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = Slurp(out);
  r.err = Slurp(err);
  return r;
}

// A valid ray set for the tiny scenes: one ray down the z axis.
std::string Rays()
{
  static std::string path = [] {
    std::vector<RayRecord> rays = {RayRecord{{0.0f, 0.0f, 10.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY}};
    std::string p = (BadInputDir() / "one.rays").string();
    WriteRays(p, rays);
    return p;
  }();
  return path;
}

// Loading a scene through `trace` must fail with exit 2 and this message.
void ExpectSceneError(const std::string& name, const std::string& text, const std::string& message)
{
  std::string path = Write(name, text);
  Result r = Run("trace " + path + " --rays " + Rays() + " --backend reference");
  INFO(name, ": exit ", r.code, ", stderr: ", r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("cellray: " + path + message) == 0);
  CHECK(r.out.empty());
}

}  // namespace

TEST_CASE("bad NFF input is rejected with FILE:LINE and exit 2")
{
  {
    Result r = Run("trace " + (BadInputDir() / "missing.nff").string() + " --rays " + Rays());
    CHECK(r.code == 2);
    CHECK(r.err.find("missing.nff: cannot open: no such file") != std::string::npos);
  }
  ExpectSceneError("empty.nff", "", ": empty scene file");
  ExpectSceneError("comments.nff", "# nothing here\n\n", ": empty scene file");
  ExpectSceneError("truncated.nff", "s 0 0 0 1\ns 1 2", ":2: truncated 's' statement (started on line 2)");
  ExpectSceneError("count.nff", "p 4\n0 0 0\n1 0 0\n1 1 0\ns 0 0 0 1\n",
                   ":5: 'p': expected a number for a vertex coordinate, got 's'");
  ExpectSceneError("word.nff", "s 1 2 x 1\n", ":1: 's': expected a number for a centre coordinate, got 'x'");
  ExpectSceneError("nan.nff", "s 0 0 0 1\ns nan 0 0 1\n", ":2: 's': a centre coordinate is not a finite number: 'nan'");
  ExpectSceneError("inf.nff", "c 0 0 0 1 0 0 inf 1\n", ":1: 'c': an apex coordinate is not a finite number: 'inf'");
  ExpectSceneError("huge.nff", "s 0 0 0 1e39\n", ":1: 's': the radius '1e39' does not fit in a float");
  ExpectSceneError("unknown.nff", "s 0 0 0 1\nq 1 2 3\n", ":2: unknown statement 'q'");
  ExpectSceneError("box.nff", "s 0 0 0 1\nbox 0 0 0 1 -1 1\n", ":2: 'box': ymin 0 is greater than ymax -1");
  ExpectSceneError("boxshort.nff", "box 0 0 0 1 1\n", ":1: truncated 'box' statement");
  ExpectSceneError("negcount.nff", "p -3\n", ":1: 'p': negative vertex count -3");
  ExpectSceneError("hugecount.nff", "p 2000000000\n0 0 0\n", ":2: truncated 'p' statement (started on line 1)");
  ExpectSceneError("view.nff", "v\nfrom 0 0 0\nat 0 0 0\nup 0 0 1\nangle 45\nhither 0\nresolution 8 8\ns 0 0 0 1\n",
                   ":1: 'v': 'from' and 'at' are the same point");
  ExpectSceneError("viewkw.nff", "v\nfrom 0 0 1\nlook 0 0 0\n", ":3: 'v' block: expected 'at', got 'look'");
  ExpectSceneError("angle.nff", "v\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 180\nhither 0\nresolution 8 8\ns 0 0 0 1\n",
                   ":1: 'v': angle 180 is not in (0, 180) degrees");
  ExpectSceneError("nogeom.nff", "b 0 0 0\nl 1 1 1\n", ": no geometry");
  ExpectSceneError("badext.xyz", "s 0 0 0 1\n", ": unknown scene format '.xyz'");
}

TEST_CASE("degenerate primitives warn, are skipped, and keep ids stable")
{
  std::string path = Write("degenerate.nff",
                           "p 2\n0 0 0\n1 0 0\n"           // id 0: 2 vertices
                           "p 3\n0 0 0\n1 0 0\n2 0 0\n"    // id 1: zero area
                           "s 5 5 5 0\n"                   // id 2: radius 0
                           "c 0 0 0 1 0 0 0 1\n"           // id 3: base == apex
                           "s 0 0 0 1\n");                 // id 4: the one hit
  std::string hits = (BadInputDir() / "degenerate.hits").string();
  Result r = Run("trace " + path + " --rays " + Rays() + " --backend reference -o " + hits);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(r.err.find(path + ":1: degenerate polygon (2 vertices, zero area): skipped, id 0 kept") != std::string::npos);
  CHECK(r.err.find(path + ":4: degenerate polygon (3 vertices, zero area): skipped, id 1 kept") != std::string::npos);
  CHECK(r.err.find(path + ":8: sphere of radius 0: skipped, id 2 kept") != std::string::npos);
  CHECK(r.err.find(path + ":9: degenerate cone (base and apex coincide): skipped, id 3 kept") != std::string::npos);
  auto h = ReadHits(hits);
  REQUIRE(h.size() == 1);
  CHECK(h[0].prim == 4u);
  CHECK(h[0].t == doctest::Approx(9.0));
}

TEST_CASE("bad OBJ and view files are rejected with FILE:LINE")
{
  ExpectSceneError("word.obj", "v 0 0 0\nv 1 x 0\n", ":2: expected a number for a vertex coordinate, got 'x'");
  ExpectSceneError("nan.obj", "v 0 0 nan\n", ":1: a vertex coordinate 'nan' is not a finite float");
  ExpectSceneError("short.obj", "v 0 0\n", ":1: 'v' needs 3 coordinates, got 2");
  ExpectSceneError("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
                   ":4: 'f': vertex index 9 is out of range (1..3 defined so far)");
  ExpectSceneError("ref.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 three\n", ":4: 'f': bad vertex reference 'three'");
  ExpectSceneError("empty.obj", "", ": empty scene file");
  ExpectSceneError("nofaces.obj", "v 0 0 0\n", ": no geometry: the file has no 'f' line");
  // tinyobjloader reads C strings; a NUL would hide the rest of its line from it.
  ExpectSceneError("nul.obj", std::string("v 0 0 0\r\nv 1 0 0 \0 9\n", 21), ":2: NUL byte: not a text file");
  // A view file may hold v, b, l and comments only.
  Write("withview.view", "l 1 1 1\ns 0 0 0 1\n");
  {
    std::string obj = Write("withview.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    Result r = Run("trace " + obj + " --rays " + Rays() + " --backend reference");
    CHECK(r.code == 2);
    CHECK(r.err.find("withview.view:2: 's' statement in a view file") != std::string::npos);
  }
  // Faces of fewer than 3 vertices warn and keep their ids.
  {
    std::string obj = Write("twoverts.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2\nf 1 2 3\n");
    std::string hits = (BadInputDir() / "twoverts.hits").string();
    Result r = Run("trace " + obj + " --rays " + Rays() + " --backend reference -o " + hits);
    CHECK(r.code == 0);
    CHECK(r.err.find(":4: face with 2 vertices: skipped, id 0 kept") != std::string::npos);
    CHECK(ReadHits(hits).at(0).prim == 1u);
  }
}

TEST_CASE("bad ray and hit files, bad command lines, unwritable output")
{
  std::string scene = Write("ok.nff", "s 0 0 0 1\n");
  {
    std::string bad = (BadInputDir() / "bad.rays").string();
    {
      std::ofstream out(bad, std::ios::binary);
      std::uint64_t n = 5;
      out.write("CRRAYS01", 8);
      out.write(reinterpret_cast<const char*>(&n), 8);
      RayRecord r = {{0, 0, 5}, 0, {0, 0, -1}, INFINITY};
      out.write(reinterpret_cast<const char*>(&r), sizeof r);
    }
    Result r = Run("trace " + scene + " --rays " + bad);
    CHECK(r.code == 2);
    CHECK(r.err.find("cellray: " + bad + ": count 5 disagrees with the file size") != std::string::npos);
  }
  {
    std::string hits = (BadInputDir() / "two.hits").string();
    WriteHits(hits, {HitRecord{1, 0, 0, 0}, HitRecord{1, 0, 0, 0}});
    Result r = Run("check " + scene + " --rays " + Rays() + " --hits " + hits);
    CHECK(r.code == 2);
    CHECK(r.err.find("2 hits for 1 rays") != std::string::npos);
  }
  {
    Result r = Run("trace " + scene + " --rays " + Rays() + " --accel kdtree");
    CHECK(r.code == 2);
    CHECK(r.err.find("cellray: unknown acceleration structure 'kdtree'") == 0);
  }
  {
    Result r = Run("rays " + scene + " --size 0x5 -o " + (BadInputDir() / "x.rays").string());
    CHECK(r.code == 2);
    CHECK(r.err.find("--size '0x5'") != std::string::npos);
  }
  for (const char* args : {"--integrator bidir", "--diffuse cube:0", "--diffuse cosine:x", "--diffuse sphere:4",
                           "--integrator path --diffuse cosine:4", "--spp 0", "--spd --integrator path",
                           "--area-lights -1", "--time-limit -2", "--depth 65"}) {
    Result r = Run("render " + scene + " --size 8x8 --no-progress " + args + " -o " + (BadInputDir() / "r.png").string());
    INFO(args, ": ", r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("cellray: ") == 0);
    CHECK_FALSE(fs::exists(BadInputDir() / "r.png"));
  }
  {
    Result r = Run("trace " + scene + " --no-such-option");
    CHECK(r.code == 2);
    CHECK(r.err.find("cellray: ") == 0);
  }
  {
    // Output into a missing directory: a runtime failure (exit 1), no file.
    fs::path out = BadInputDir() / "no-such-dir" / "x.hits";
    Result r = Run("trace " + scene + " --rays " + Rays() + " -o " + out.string());
    CHECK(r.code == 1);
    CHECK(r.err.find("cannot write") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
}

TEST_CASE("render without its image module: a runtime error (exit 1) before the work and no file, while trace never needs it")
{
  std::string scene = Write("nomodule.nff", "s 0 0 0 1\n");
  const std::string env = "CELLRAY_IMAGE_MODULE=" + (BadInputDir() / "no-such-module.so").string() + " ";
  fs::path img = BadInputDir() / "nomodule.png", err = BadInputDir() / "nm_err.txt";
  std::string cmd = env + CELLRAY_BINARY + std::string(" render ") + scene + " --size 8x8 --no-progress -o " +
                    img.string() + " >/dev/null 2>" + err.string();
  int status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 1);
  const std::string e = Slurp(err);
  CHECK(e.find("cellray: image support (libcellray_image.so, OpenImageIO) cannot be loaded: tried ") == 0);
  CHECK(e.find("no-such-module.so (absent)") != std::string::npos);
  CHECK_FALSE(fs::exists(img));
  // An unsupported format is bad input, told before the module is looked for.
  cmd = env + CELLRAY_BINARY + std::string(" render ") + scene + " --size 8x8 --no-progress -o " +
        (BadInputDir() / "x.bmp").string() + " >/dev/null 2>" + err.string();
  status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 2);
  CHECK(Slurp(err).find("unsupported image format (use .png or .exr)") != std::string::npos);
  // Tracing writes no image and does not load the module.
  cmd = env + CELLRAY_BINARY + std::string(" trace ") + scene + " --rays " + Rays() + " >/dev/null 2>" + err.string();
  status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}

TEST_CASE("generated scenes (gen:KIND:N) load in rays and trace as in bench, and bad names are exit 2")
{
  const std::string rays = (BadInputDir() / "gen.rays").string();
  Result r = Run("rays gen:sphereflake:1 --size 16x16 -o " + rays);
  REQUIRE(r.code == 0);
  const std::string hits = (BadInputDir() / "gen.hits").string();
  r = Run("trace gen:sphereflake:1 --rays " + rays + " --backend simd -o " + hits);
  CHECK(r.code == 0);
  CHECK(r.out.find("\"scene\":\"gen:sphereflake:1\"") != std::string::npos);
  CHECK(r.out.find("\"hits\":0,") == std::string::npos);  // the flake is in view
  r = Run("check gen:sphereflake:1 --rays " + rays + " --hits " + hits);
  CHECK(r.code == 0);
  CHECK(r.out.find("\"wrong\":0,") != std::string::npos);
  for (const char* bad : {"gen:teapots:3", "gen:stadium:x", "gen:stadium"}) {
    r = Run(std::string("trace ") + bad + " --rays " + rays);
    INFO(bad, ": ", r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(std::string("cellray: scene '") + bad + "': ") == 0);
  }
}

TEST_CASE("no OpenCL platform: the default backend falls back to simd with one warning line")
{
  std::string scene = Write("fallback.nff", "s 0 0 0 1\n");
  fs::create_directories(BadInputDir() / "no-vendors");
  const std::string env = "OCL_ICD_VENDORS=" + (BadInputDir() / "no-vendors").string() + " ";
  fs::path out = BadInputDir() / "fb_out.txt", err = BadInputDir() / "fb_err.txt";
  std::string cmd = env + CELLRAY_BINARY + std::string(" trace ") + scene + " --rays " + Rays() + " >" + out.string() +
                    " 2>" + err.string();
  int status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  std::string e = Slurp(err), o = Slurp(out);
  const std::string warning = "cellray: warning: no OpenCL platform";
  const auto at = e.find(warning);
  CHECK(at != std::string::npos);
  CHECK(e.find(warning, at + 1) == std::string::npos);  // one line, once
  CHECK(o.find("\"backend\":\"simd\"") != std::string::npos);
  // Asking for OpenCL explicitly is a runtime failure (exit 1), not a fallback.
  cmd = env + CELLRAY_BINARY + std::string(" trace ") + scene + " --rays " + Rays() + " --backend opencl >" +
        out.string() + " 2>" + err.string();
  status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 1);
  CHECK(Slurp(err).find("cellray: OpenCL: no platform found") != std::string::npos);
}
