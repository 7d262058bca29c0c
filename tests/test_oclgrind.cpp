// Every OpenCL kernel configuration under Oclgrind, the OpenCL device
// simulator that reports invalid memory accesses, reads of uninitialised
// values, data races (local and global) and API misuse: structure (grid,
// octree, BVH) x variant (ray, packet) x query (closest, occlusion) x
// precision (fast, robust, fp64) x primitive-type set (every non-empty subset
// of spheres, triangles, cones, and boxes with quadrics and polyhedra: the backend compiles
// only the types a scene has), 288 configurations, the 12 robust ones with every type again with
// their cold paths inlined (CELLRAY_CL_COLD=inline), plus the camera kernels with counters,
// the generic programs and the renderer's unified hits. Each runs the real
// binary as `oclgrind --data-races --uninitialized --check-api cellray trace
// ...` on a few rays of a small scene and must exit 0 with nothing in
// Oclgrind's log and nothing on stderr, and answer as PoCL does (closest hit:
// the same record, bit for bit; occlusion: the same occluded flags).
//
// Oclgrind 21.10 cannot run the llvm.experimental.noalias.scope.decl
// intrinsic that an optimised build of the packet kernels contains (its
// clCreateKernel fails with CL_INVALID_KERNEL_NAME), so the programs are
// built with -cl-opt-disable, into a program cache of their own (the wrapper's
// build options are not part of the cache key). The last test case checks
// that the optimised build fails by name and leaves nothing in the cache.
//
// The oracle is PoCL's generic per-ray program of the same precision
// (--variant ray-generic: every type and structure, chosen by arguments),
// the same traversal code as every specialised program; it is compiled once
// per precision (about 9 s cold on the CI machine) where 288 specialised
// PoCL programs would take minutes. Skipped, loudly, without oclgrind or
// without an OpenCL device. Cost: docs/OPENCL.md, "Checked under Oclgrind".
// A last test registers Oclgrind's ICD beside the installed ones and checks
// that the default device and `--backend auto` do not change.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "host/cl/cl_device.h"
#include "host/core/error.h"
#include "host/io/rays_io.h"
#include "host/render/image_io.h"
#include "host/scene/camera.h"
#include "tests/test_util.h"

using namespace cr;
namespace fs = std::filesystem;
using cr::test::BuildDir;
using cr::test::Slurp;

namespace {


// The oclgrind wrapper on $PATH, empty when it is not installed.
std::string OclgrindPath()
{
  const char* path = std::getenv("PATH");
  std::stringstream ss(path ? path : "");
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    const fs::path p = fs::path(dir.empty() ? "." : dir) / "oclgrind";
    if (::access(p.c_str(), X_OK) == 0) return p.string();
  }
  return {};
}

// True when the tests cannot run; prints why, once, on stderr.
bool NoOclgrind()
{
  static const bool none = [] {
    std::string why;
    if (OclgrindPath().empty()) {
      why = "oclgrind is not installed (scripts/install-deps.sh installs it)";
    } else {
      try {
        bool device = false;
        for (const auto& d : ListClDevices()) device = device || !d.simulator;
        if (device) return false;
        why = "no OpenCL device besides Oclgrind to compare with";
      } catch (const std::exception& e) {
        why = e.what();
      }
    }
    std::fprintf(stderr, "cellray_tests: *** Oclgrind tests SKIPPED: %s ***\n", why.c_str());
    return true;
  }();
  return none;
}


// This process's scratch directory, removed when the process ends.
fs::path OclgrindDir()
{
  static const struct Scratch {
    fs::path dir = BuildDir() / "test-cache" / fmt::format("oclgrind-{}", ::getpid());
    Scratch()
    {
      fs::remove_all(dir);
      fs::create_directories(dir);
    }
    ~Scratch()
    {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } scratch;
  return scratch.dir;
}

struct TypeSet {
  const char* name;
  bool spheres, triangles, cones, boxes = false, quadrics = false, polyhedra = false, sdfs = false, csgs = false;
};
// Each SPD type alone, the three together, then the NFF extensions' types
// together (box, quadric, polyhedron, SDF block and CSG solid: one set, each
// program holding the five). The pairs (st, sc, tc) hold no code that stc
// lacks and no layout that s, t and c do not cover: dropped on 2026-11-28
// (40 s of CI time).
constexpr TypeSet kTypeSets[] = {{"s", true, false, false},
                                 {"t", false, true, false},
                                 {"c", false, false, true},
                                 {"stc", true, true, true},
                                 {"bqhfg", false, false, false, true, true, true, true, true}};
constexpr const TypeSet& kEveryType = kTypeSets[3];   // the SPD's every type (stc)
constexpr const TypeSet& kExtensions = kTypeSets[4];  // the NFF extensions' types (bqhfg)

// A 3 x 3 x 2 block of primitives, the set's types in turn: 18 primitives,
// enough for interior BVH nodes (leaves of 4), a subdivided octree (leaves
// of 12) and a grid of many cells, and small enough for the simulator.
std::string SceneText(const TypeSet& ts)
{
  std::vector<char> types;
  if (ts.spheres) types.push_back('s');
  if (ts.triangles) types.push_back('t');
  if (ts.cones) types.push_back('c');
  if (ts.boxes) types.push_back('b');
  if (ts.quadrics) types.push_back('q');
  if (ts.polyhedra) types.push_back('h');
  if (ts.sdfs) types.push_back('f');
  if (ts.csgs) types.push_back('g');
  std::string s =
      "b 0.1 0.1 0.1\nv\nfrom 0.3 -6 1.2\nat 0 0 0.55\nup 0 0 1\nangle 30\nhither 0.01\nresolution 4 4\n"
      "l 3 -6 6\nf 0.8 0.5 0.3 0.6 0.2 20 0.3 1.3\n";
  int k = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int z = 0; z < 2; ++z) {
        const double x = (i - 1) * 1.2, y = (j - 1) * 1.2, h = z * 1.1;
        switch (types[std::size_t(k++) % types.size()]) {
          case 's': s += fmt::format("s {} {} {} 0.45\n", x, y, h); break;
          case 't':
            s += fmt::format("p 3\n{} {} {}\n{} {} {}\n{} {} {}\n", x - 0.5, y, h - 0.4, x + 0.5, y + 0.2, h - 0.4, x,
                             y - 0.1, h + 0.5);
            break;
          case 'c': s += fmt::format("c {} {} {} 0.4 {} {} {} 0.1\n", x, y, h - 0.4, x, y + 0.1, h + 0.4); break;
          case 'b': s += fmt::format("box {} {} {} {} {} {}\n", x - 0.4, y - 0.3, h - 0.4, x + 0.4, y + 0.3, h); break;
          case 'q':  // an ellipsoid with a tilt (xz term), clipped at its top
            s += fmt::format("quadric 4 9 6 0 2 0 {} {} {} {} {} {} {} {} {} {}\n", -8 * x - 2 * h, -18 * y,
                             -12 * h - 2 * x, 4 * x * x + 9 * y * y + 6 * h * h + 2 * x * h - 1, x - 0.6, y - 0.4,
                             h - 0.5, x + 0.6, y + 0.4, h + 0.3);
            break;
          case 'h':  // a tilted tetrahedron-like wedge: 5 planes about (x, y, h)
            s += fmt::format("polyhedron 5\n0 0 -1 {}\n0.8 0 0.6 {}\n-0.8 0 0.6 {}\n0 0.8 0.6 {}\n0 -0.8 0.6 {}\n",
                             h - 0.4, -0.8 * x - 0.6 * h - 0.3, 0.8 * x - 0.6 * h - 0.3, -0.8 * y - 0.6 * h - 0.3,
                             0.8 * y - 0.6 * h - 0.3);
            break;
          case 'g':  // a CSG solid: a lens of two spheres minus a box notch
            s += fmt::format("csg difference\n  csg intersection\n    s {} {} {} 0.45\n    s {} {} {} 0.45\n  csg end\n"
                             "  box {} {} {} {} {} {}\ncsg end\n",
                             x - 0.2, y, h, x + 0.2, y, h, x - 0.1, y - 0.5, h, x + 0.1, y + 0.5, h + 0.5);
            break;
          case 'f':  // an SDF block: a ball smoothly joined to a box, relaxed marching
            s += fmt::format("sdf {} {} {} {} {} {} 0.001 64 1.5\n  sphere {} {} {} 0.3\n  box {} {} {} 0.35 0.2 0.2\n"
                             "  smooth 0.1\nsdf end\n",
                             x - 0.5, y - 0.5, h - 0.5, x + 0.5, y + 0.5, h + 0.5, x, y, h + 0.1, x, y, h - 0.15);
            break;
        }
      }
  return s;
}

// A type set's scene and its rays (files under OclgrindDir()): 16 primary rays (a
// 4x4 image), 8 random rays with origins inside the scene box, and the shadow
// rays of the primary hits, in that order; with 4x4 packets the last packet
// has dead lanes.
struct Fixture {
  std::string scene, rays;
  std::vector<RayRecord> records;
};

const Fixture& GetFixture(const TypeSet& ts)
{
  static std::map<std::string, Fixture> cache;
  Fixture& f = cache[ts.name];
  if (!f.scene.empty()) return f;
  f.scene = (OclgrindDir() / fmt::format("{}.nff", ts.name)).string();
  std::ofstream(f.scene) << SceneText(ts);
  const Scene& scene = test::CachedScene(f.scene);
  const auto& ref = test::CachedReference(scene);
  RayGenOptions g;
  g.width = g.height = 4;
  f.records = GenerateRays(scene, ref, g);
  g.kind = RayKind::Random;
  g.count = 8;
  for (const auto& r : GenerateRays(scene, ref, g)) f.records.push_back(r);
  g.kind = RayKind::Shadow;
  g.count = 0;
  for (const auto& r : GenerateRays(scene, ref, g)) f.records.push_back(r);
  f.rays = (OclgrindDir() / fmt::format("{}.rays", ts.name)).string();
  WriteRays(f.rays, f.records);
  return f;
}

struct Outcome {
  int code = -1;
  std::string out, err, log;
};

// Runs `cellray <args>` under oclgrind with every check on. The programs go
// to a cache of their own under the build tree; $CELLRAY_DEVICE is cleared
// (under the wrapper Oclgrind is the only device) and so is any injected fault.
Outcome RunUnderOclgrind(const std::string& args, const std::string& tag, bool optimised = false,
                         const fs::path& cacheDir = BuildDir() / "test-cache" / "oclgrind", const std::string& env = "")
{
  const fs::path log = OclgrindDir() / (tag + ".log"), out = OclgrindDir() / (tag + ".out"), err = OclgrindDir() / (tag + ".err");
  const std::string cmd = fmt::format(
      "env -u CELLRAY_DEVICE -u CELLRAY_CL_FAULT -u CELLRAY_CL_COLD {}CELLRAY_CACHE_DIR={} {} --log {} {}--data-races "
      "--uninitialized --check-api {} {} > {} 2> {}",
      env, cacheDir.string(), OclgrindPath(), log.string(), optimised ? "" : "--build-options -cl-opt-disable ",
      CELLRAY_BINARY, args, out.string(), err.string());
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = Slurp(out);
  o.err = Slurp(err);
  o.log = Slurp(log);
  return o;
}

// PoCL's answers: its generic per-ray program (one per precision), the
// structure built as cellray trace builds it: the configuration and the hits.
TraceConfig PoclConfig(AccelKind accel, Precision precision)
{
  TraceConfig cfg;
  cfg.backend = Backend::OpenCL;
  cfg.accel = accel;
  cfg.precision = precision;
  cfg.variant = "ray-generic";
  return cfg;
}
std::vector<HitRecord> PoclHits(const Fixture& f, AccelKind accel, Precision precision, bool occlusion)
{
  std::vector<HitRecord> hits;
  CreateTracer(test::CachedScene(f.scene), PoclConfig(accel, precision))->Trace(f.records, hits, occlusion, nullptr);
  return hits;
}

// Closest hit: the same record bit for bit; occlusion: the same verdict.
// Returns the number of rays that differ and describes the first.
std::size_t Differ(const std::vector<HitRecord>& a, const std::vector<HitRecord>& b, bool occlusion, std::string& first)
{
  if (a.size() != b.size()) {
    first = fmt::format("{} hits against {}", a.size(), b.size());
    return std::max(a.size(), b.size());
  }
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool same = occlusion ? (a[i].prim == CR_NO_HIT) == (b[i].prim == CR_NO_HIT)
                                : std::memcmp(&a[i], &b[i], sizeof(HitRecord)) == 0;
    if (!same && n++ == 0)
      first = fmt::format("ray {}: oclgrind (t {}, prim {}) pocl (t {}, prim {})", i, a[i].t, a[i].prim, b[i].t,
                          b[i].prim);
  }
  return n;
}

// Checks one run: exit 0, Oclgrind's log and stderr empty.
void CheckClean(const Outcome& o, const std::string& what)
{
  INFO(what, ": exit ", o.code, "\nstderr: ", o.err.substr(0, 2000), "\noclgrind log: ", o.log.substr(0, 4000));
  CHECK(o.code == 0);
  CHECK(o.log.empty());
  CHECK(o.err.empty());
}

constexpr auto& kAccels = kAccelKinds;

// Whether a sweep of `precision` visits type set `ts`. Robust mode, whose
// kernels hold every cold path, visits every set; fast and fp64 (the same
// traversal, fewer paths) the two largest (stc, bqhfg), which hold each
// type's code (triangles alone, the meshes' program, dropped from these two
// on 2026-11-28: 35 s of CI time for code that stc and robust's t run).
bool SweepVisits(Precision precision, const TypeSet& ts)
{
  return precision == Precision::Robust || &ts == &kEveryType || &ts == &kExtensions;
}

// Every type set (SweepVisits) x structure x query for one precision and
// variant; `coldInline`: the cold paths inlined (CELLRAY_CL_COLD=inline, the
// form offered for GPUs; host/cl/cl_options.cpp), with every type only (6
// runs: the program that holds every cold path).
// `octreeArgs`: the octree alone, with every type, built and walked with
// these structure options (the ray-margin octree's programs, built apart).
void Sweep(Precision precision, const char* variant, bool coldInline = false, const char* octreeArgs = nullptr)
{
  auto cache = test::OpenCLTestCacheDir();
  int runs = 0;
  for (const TypeSet& ts : kTypeSets) {
    if ((coldInline || octreeArgs) && &ts != &kEveryType) continue;
    if (!SweepVisits(precision, ts)) continue;
    const Fixture& f = GetFixture(ts);
    for (AccelKind accel : kAccels)
      for (bool occlusion : {false, true}) {
        if (octreeArgs && accel != AccelKind::Octree) continue;
        // Occlusion in robust mode only: the any-hit query is the same code
        // in every precision (the walk's early exit), which robust's sweep
        // runs on every set; fast and fp64 differ in their intersectors,
        // which closest hits run.
        if (occlusion && precision != Precision::Robust) continue;
        // The hierarchical grid's packet call is its per-ray walk run by each
        // lane (kernels/hgrid_packet.cl): the per-ray sweeps cover the walk
        // on every type set, the packet sweeps its glue on the every-type one.
        if (accel == AccelKind::HGrid && std::string(variant) == "packet" && &ts != &kEveryType) continue;
        // The stackless walk is the BVH's; its reads (parent links after the
        // references) do not depend on the types: the every-type set.
        if (std::string(variant) == "stackless" && (accel != AccelKind::BVH || &ts != &kEveryType)) continue;
        // The wide walk is the BVH's too: its triangle packs (t, stc) and the
        // other types' ids and mixed leaves (stc, bqhfg).
        if (std::string(variant) == "wide" && (accel != AccelKind::BVH || &ts == &kTypeSets[0] || &ts == &kTypeSets[2]))
          continue;
        // The wide packet walk: its node steps and lanes (t, stc).
        if (std::string(variant) == "wide-packet" && (accel != AccelKind::BVH || (&ts != &kTypeSets[1] && &ts != &kEveryType)))
          continue;
        const std::string what = fmt::format("{} {} {}:4x4 {} {}", ts.name, AccelKindName(accel), variant,
                                             occlusion ? "occlusion" : "closest", PrecisionName(precision));
        const std::string tag = fmt::format("{}-{}-{}-{}-{}{}{}", ts.name, AccelKindName(accel), variant,
                                            occlusion ? "o" : "c", PrecisionName(precision),
                                            coldInline ? "-inline" : "", octreeArgs ? "-margin" : "");
        const std::string hitsPath = (OclgrindDir() / (tag + ".hits")).string();
        const Outcome o = RunUnderOclgrind(
            fmt::format("trace {} --rays {} --backend opencl --accel {} --variant {}:4x4 --precision {}{}{}{} -o {}",
                        f.scene, f.rays, AccelKindName(accel), variant, PrecisionName(precision),
                        occlusion ? " --occlusion" : "", octreeArgs ? " " : "", octreeArgs ? octreeArgs : "",
                        hitsPath),
            tag, false, BuildDir() / "test-cache" / "oclgrind", coldInline ? "CELLRAY_CL_COLD=inline " : "");
        ++runs;
        CheckClean(o, what);
        if (o.code != 0) continue;
        std::string first;
        const std::size_t n = Differ(ReadHits(hitsPath), PoclHits(f, accel, precision, occlusion), occlusion, first);
        INFO(what, ": ", first);
        CHECK(n == 0);
      }
  }
  MESSAGE(runs, " configurations (", std::string(PrecisionName(precision)), ", ", std::string(variant),
          std::string(coldInline ? ", cold paths inlined" : ""), std::string(octreeArgs ? ", " : ""),
          std::string(octreeArgs ? octreeArgs : ""), ") under oclgrind");
  CHECK(runs > 0);
}

}  // namespace

TEST_CASE("oclgrind: per-ray kernels, fast, types stc bqhfg x structure, closest hits" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Fast, "ray");
}

TEST_CASE("oclgrind: per-ray kernels, robust, types s t c stc bqhfg x structure x query" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Robust, "ray");
}

TEST_CASE("oclgrind: per-ray kernels, fp64, types stc bqhfg x structure, closest hits" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Fp64, "ray");
}

// The stackless BVH walk reads each node's parent after the references.
TEST_CASE("oclgrind: stackless BVH walk, robust, every type x query" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Robust, "stackless");
}

// The wide BVH walk reads the 8-wide layout (nodes, packs, leaves) with
// vector loads.
TEST_CASE("oclgrind: wide BVH walk, robust, types t stc bqhfg x query" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Robust, "wide");
}

TEST_CASE("oclgrind: wide BVH walk, fast, types stc bqhfg, closest hits" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Fast, "wide");
}

// Eight rays per work-item through the wide layout.
TEST_CASE("oclgrind: wide packet BVH walk, robust, types t stc x query" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Robust, "wide-packet");
}

TEST_CASE("oclgrind: packet kernels, fast, types stc bqhfg x structure, closest hits" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Fast, "packet");
}

TEST_CASE("oclgrind: packet kernels, robust, types s t c stc bqhfg x structure x query" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Robust, "packet");
}

// The robust programs with their cold paths inlined (CELLRAY_CL_COLD=inline):
// fast and fp64 programs have none, so they are the same either way.
TEST_CASE("oclgrind: per-ray and packet kernels, robust, cold paths inlined, types stc x structure x query" *
          doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Robust, "ray", true);
  Sweep(Precision::Robust, "packet", true);
}

// The octree with the ray's margins: its own programs (CR_OCTREE_MARGIN_BUILD),
// on Oclgrind (a "gpu" device) in the GPU's form, each level's parameters
// recomputed from the planes (CR_OCTREE_KEEP_FRAMES=0); the answers PoCL's
// classic octree gives (the same closest hits, the same occluded flags).
TEST_CASE("oclgrind: the ray-margin octree (--octree-margin ray), per-ray and packet kernels, robust, every type x query" *
          doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Robust, "ray", false, "--octree-margin ray --octree-root offset");
  Sweep(Precision::Robust, "packet", false, "--octree-margin ray --octree-root offset");
}

TEST_CASE("oclgrind: packet kernels, fp64, types stc bqhfg x structure, closest hits" * doctest::skip(NoOclgrind()))
{
  Sweep(Precision::Fp64, "packet");
}

TEST_CASE("oclgrind: camera kernels with counters, generic programs, unified hits" * doctest::skip(NoOclgrind()))
{
  auto cache = test::OpenCLTestCacheDir();
  const Fixture& f = GetFixture(kEveryType);  // every type
  const Scene& scene = test::CachedScene(f.scene);
  const int w = 5, h = 3;  // partial 4x4 tiles in both directions
  int runs = 0, pair = 0;
  for (AccelKind accel : kAccels)
    for (const char* variant : {"ray", "packet"}) {
      // Primary rays generated on the device (Trace_Primary*), counters on,
      // in one precision per structure and variant, in turn (the camera
      // code is the same in all three; the per-ray sweeps above run each
      // precision's intersectors on every structure and variant).
      const Precision precisions[] = {Precision::Fast, Precision::Robust, Precision::Fp64};
      {
        const Precision precision = precisions[pair++ % 3];
        const std::string tag = fmt::format("cam-{}-{}-{}", AccelKindName(accel), variant, PrecisionName(precision));
        const std::string hitsPath = (OclgrindDir() / (tag + ".hits")).string();
        const Outcome o = RunUnderOclgrind(
            fmt::format("trace {} --primary {}x{} --stats --backend opencl --accel {} --variant {}:4x4 --precision {} "
                        "-o {}",
                        f.scene, w, h, AccelKindName(accel), variant, PrecisionName(precision), hitsPath),
            tag);
        ++runs;
        CheckClean(o, tag);
        if (o.code == 0) {
          std::vector<HitRecord> ref;
          CreateTracer(scene, PoclConfig(accel, precision))->TracePrimary(MakeCameraFrame(scene.camera, w, h), w, h, ref, nullptr);
          std::string first;
          const std::size_t n = Differ(ReadHits(hitsPath), ref, false, first);
          INFO(tag, ": ", first);
          CHECK(n == 0);
        }
      }
      // The generic programs (every type and structure, chosen by arguments).
      for (bool occlusion : {false, true}) {
        const std::string tag = fmt::format("gen-{}-{}-{}", AccelKindName(accel), variant, occlusion ? "o" : "c");
        const std::string hitsPath = (OclgrindDir() / (tag + ".hits")).string();
        const Outcome o = RunUnderOclgrind(fmt::format("trace {} --rays {} --backend opencl --accel {} --variant "
                                                       "{}-generic:4x4{} -o {}",
                                                       f.scene, f.rays, AccelKindName(accel), variant,
                                                       occlusion ? " --occlusion" : "", hitsPath),
                                           tag);
        ++runs;
        CheckClean(o, tag);
        if (o.code != 0) continue;
        std::string first;
        const std::size_t n =
            Differ(ReadHits(hitsPath), PoclHits(f, accel, Precision::Robust, occlusion), occlusion, first);
        INFO(tag, ": ", first);
        CHECK(n == 0);
      }
      // The renderer: unified hit records, closest and shadow queries; the
      // image must equal the scalar backend's pixel for pixel.
      const std::string tag = fmt::format("render-{}-{}", AccelKindName(accel), variant);
      const std::string image = (OclgrindDir() / (tag + ".exr")).string(), refImage = (OclgrindDir() / (tag + "-ref.exr")).string();
      const Outcome o = RunUnderOclgrind(fmt::format("render {} --size 6x4 --no-progress --backend opencl --accel {} "
                                                     "--variant {}:4x4 -o {}",
                                                     f.scene, AccelKindName(accel), variant, image),
                                         tag);
      ++runs;
      CheckClean(o, tag);
      if (o.code != 0) continue;
      const std::string cmd = fmt::format("{} render {} --size 6x4 --no-progress --backend scalar --accel {} -o {} "
                                          "> /dev/null",
                                          CELLRAY_BINARY, f.scene, AccelKindName(accel), refImage);
      REQUIRE(std::system(cmd.c_str()) == 0);
      int wa = 0, ha = 0, wb = 0, hb = 0;
      const std::vector<float> a = ReadImage(image, wa, ha), b = ReadImage(refImage, wb, hb);
      INFO(tag);
      CHECK(wa == 6);
      CHECK(ha == 4);
      CHECK(a == b);
    }
  MESSAGE(runs, " further configurations under oclgrind (camera + counters, generic, render)");
}

TEST_CASE("oclgrind: a program it cannot run fails by name and is not cached" * doctest::skip(NoOclgrind()))
{
  // Optimised, the packet kernels hold llvm.experimental.noalias.scope.decl,
  // which Oclgrind 21.10 does not know: the program builds, its kernel
  // cannot be created. Before the fix the program was stored in the cache
  // at the build, so every later run loaded it and failed the same way.
  const fs::path cacheDir = OclgrindDir() / "cache";
  const Fixture& f = GetFixture(kTypeSets[0]);
  const Outcome o = RunUnderOclgrind(
      fmt::format("trace {} --rays {} --backend opencl --variant packet:4x4", f.scene, f.rays), "optimised", true,
      cacheDir);
  INFO("exit ", o.code, ", stderr: ", o.err.substr(0, 2000));
  if (o.code == 0) {
    // A later Oclgrind that runs the intrinsic: then the program is good
    // and cached, and there is nothing to check here.
    MESSAGE("this Oclgrind runs optimised packet kernels; nothing to check");
  } else {
    CHECK(o.code == kExitRuntime);
    CHECK(o.err.find("cellray: OpenCL: clCreateKernel failed: CL_INVALID_KERNEL_NAME") != std::string::npos);
    CHECK(o.err.find("(the program is not cached)") != std::string::npos);
    std::size_t nEntries = 0;
    if (fs::exists(cacheDir))
      for (const auto& e : fs::directory_iterator(cacheDir)) nEntries += e.path().extension() == ".clbin";
    CHECK(nEntries == 0);
  }
}

TEST_CASE("oclgrind: a registered Oclgrind ICD changes no default choice" * doctest::skip(NoOclgrind()))
{
  // The Debian package registers no ICD; someone may. A vendors directory
  // with every installed ICD plus Oclgrind's, named to come first.
  const fs::path icd = fs::path(OclgrindPath()).parent_path().parent_path() / "lib" / "oclgrind" /
                       "liboclgrind-rt-icd.so";
  const fs::path vendors = "/etc/OpenCL/vendors";
  if (!fs::exists(icd) || !fs::exists(vendors)) {
    MESSAGE("no ", icd.string(), " or ", vendors.string(), ": nothing to register");
    return;
  }
  const fs::path dir = OclgrindDir() / "vendors";
  fs::create_directories(dir);
  for (const auto& e : fs::directory_iterator(vendors))
    if (e.path().extension() == ".icd") fs::copy_file(e.path(), dir / e.path().filename());
  std::ofstream(dir / "0-oclgrind.icd") << icd.string() << "\n";
  const Fixture& f = GetFixture(kEveryType);
  auto run = [&](const std::string& args) {
    const fs::path out = OclgrindDir() / "icd.out", err = OclgrindDir() / "icd.err";
    const std::string cmd =
        fmt::format("env -u CELLRAY_DEVICE OCL_ICD_VENDORS={} CELLRAY_CACHE_DIR={} {} {} > {} 2> {}", dir.string(),
                    (BuildDir() / "test-cache" / "opencl").string(), CELLRAY_BINARY, args, out.string(), err.string());
    const int status = std::system(cmd.c_str());
    INFO(args, "\nstderr: ", Slurp(err));
    REQUIRE(WIFEXITED(status));
    REQUIRE(WEXITSTATUS(status) == 0);
    return nlohmann::json::parse(Slurp(out));
  };
  const nlohmann::json info = run("info");
  std::vector<std::pair<std::string, bool>> devices;  // name, simulator
  bool realGpu = false;
  for (const auto& p : info["opencl_platforms"])
    for (const auto& d : p["devices"]) {
      devices.emplace_back(d["name"].get<std::string>(), d["simulator"].get<bool>());
      realGpu = realGpu || (d["type"] == "gpu" && !d["simulator"].get<bool>());
    }
  REQUIRE(devices.size() >= 2);
  CHECK(devices.back().first == "Oclgrind Simulator");  // listed last...
  CHECK(devices.back().second);
  CHECK_FALSE(devices.front().second);  // ...after the real devices, whose numbers stay
  const std::string trace = fmt::format("trace {} --rays {}", f.scene, f.rays);
  // `auto` does not take the simulator for a GPU, nor the default choice for
  // a device.
  CHECK(run(trace)["backend"] == (realGpu ? "opencl" : "simd"));
  CHECK(run(trace + " --backend opencl")["device"] != "Oclgrind Simulator");
  CHECK(run(fmt::format("{} --backend opencl --device {}", trace, devices.size() - 1))["device"] ==
        "Oclgrind Simulator");
}
