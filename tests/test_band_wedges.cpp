// The wedges of --distribute bands-data (host/mpi/band_tracer.h), without
// MPI: every point of a box lies in a wedge the box is given to; a ray's run
// of wedges, cut at its Exit points, puts every point of the ray in the
// wedge the run names; the primary rays of a band never leave its wedge.
#include <cmath>
#include <random>

#include "host/mpi/band_tracer.h"
#include "host/scene/camera.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

double AngleOf(const BandWedges& w, const glm::dvec3& p)
{
  const glm::dvec2 q = w.Project(p);
  return std::atan2(q.y, q.x);
}

// Away from the boundaries (by more than `margin` radians) and the axis.
bool Clear(const BandWedges& w, const glm::dvec3& p, double margin)
{
  const glm::dvec2 q = w.Project(p);
  if (glm::length(q) < 1e-3) return false;
  const double a = std::atan2(q.y, q.x);
  for (double b : w.upper)
    if (std::abs(a - b) < margin) return false;
  return true;
}

CameraFrame Frame(std::mt19937& rng)
{
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  Camera c;
  c.from = glm::vec3(float(u(rng)), float(u(rng)), float(u(rng)));
  c.at = glm::vec3(float(u(rng)), float(u(rng)), float(u(rng)));
  c.up = glm::vec3(float(u(rng)), float(u(rng)), float(u(rng)));
  c.angle = float(20.0 + 3.0 * std::abs(u(rng)));
  return MakeCameraFrame(c, 64, 48);
}

}  // namespace

TEST_CASE("band wedges: a box's wedges hold every point of the box")
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0), s(0.0, 1.0);
  int checked = 0, missed = 0, disagree = 0;
  for (int cam = 0; cam < 20; ++cam) {
    const CameraFrame f = Frame(rng);
    for (int n : {2, 3, 5, 8}) {
      const BandWedges w = BandWedges::ForRows(f, n);
      REQUIRE(w.Count() == n);
      for (int b = 0; b < 50; ++b) {
        Bounds box;
        const glm::dvec3 c(u(rng), u(rng), u(rng));
        const double size = std::pow(10.0, -3.0 + 4.0 * s(rng));
        box.Extend(glm::vec3(c));
        box.Extend(glm::vec3(c + size * glm::dvec3(s(rng), s(rng), s(rng))));
        const std::vector<bool> in = w.WedgesOfBox(box);
        for (int k = 0; k < 40; ++k) {
          const glm::dvec3 p = glm::dvec3(box.lo) + glm::dvec3(s(rng), s(rng), s(rng)) * glm::dvec3(box.Extent());
          const int at = w.WedgeOf(AngleOf(w, p));
          missed += !in[std::size_t(at)];
          if (Clear(w, p, 1e-9)) disagree += w.WedgeOfPoint(w.Project(p)) != at;
          ++checked;
        }
      }
      // A box around the eye's horizontal line meets every wedge.
      Bounds axis;
      axis.Extend(glm::vec3(f.eye + 5.0 * f.right - 0.1 * (f.up + f.forward)));
      axis.Extend(glm::vec3(f.eye + 5.0 * f.right + 0.1 * (f.up + f.forward)));
      for (bool b : w.WedgesOfBox(axis)) CHECK(b);
    }
  }
  CHECK(checked == 20 * 4 * 50 * 40);
  CHECK(missed == 0);
  CHECK(disagree == 0);  // WedgeOfPoint's cross products agree with the angle
}

TEST_CASE("band wedges: a ray's run names the wedge of each of its points")
{
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-20.0, 20.0), s(0.0, 1.0);
  int checked = 0, multi = 0, wrong = 0;
  for (int cam = 0; cam < 10; ++cam) {
    const CameraFrame f = Frame(rng);
    for (int n : {2, 4, 7}) {
      const BandWedges w = BandWedges::ForRows(f, n);
      for (int r = 0; r < 300; ++r) {
        RayRecord ray{};
        const glm::dvec3 o(u(rng), u(rng), u(rng));
        glm::dvec3 d(u(rng), u(rng), u(rng));
        d = glm::normalize(d);
        for (int a = 0; a < 3; ++a) ray.org[a] = float(o[a]), ray.dir[a] = float(d[a]);
        ray.tmin = r % 3 == 0 ? 0.0f : float(s(rng));
        ray.tmax = r % 2 == 0 ? INFINITY : float(1.0 + 60.0 * s(rng));
        const BandWedges::Run run = w.RunOf(ray);
        REQUIRE(run.hops >= 0);
        REQUIRE(run.hops < n);
        multi += run.hops > 0;
        std::vector<double> exits;
        double prev = ray.tmin;
        for (int k = 0; k <= run.hops; ++k) exits.push_back(prev = w.Exit(ray, run, k, prev));
        const double tEnd = std::isinf(ray.tmax) ? 1e4 : double(ray.tmax);
        for (int q = 0; q <= 200; ++q) {
          const double t = double(ray.tmin) + (tEnd - double(ray.tmin)) * q / 200.0;
          const glm::dvec3 p = glm::dvec3(ray.org[0], ray.org[1], ray.org[2]) +
                               t * glm::dvec3(ray.dir[0], ray.dir[1], ray.dir[2]);
          if (!Clear(w, p, 1e-6)) continue;
          int k = 0;
          while (k < run.hops && t > exits[std::size_t(k)]) ++k;
          if (w.WedgeOf(AngleOf(w, p)) != w.At(run, k)) {
            if (!wrong) MESSAGE("first wrong: camera ", cam, " n ", n, " ray ", r, " t ", t);
            ++wrong;
          }
          ++checked;
        }
      }
    }
  }
  CHECK(wrong == 0);
  CHECK(checked > 100000);
  CHECK(multi > 1000);  // the runs cross wedges
}

TEST_CASE("band wedges: the primary rays of a band stay in its wedge")
{
  Camera c;
  c.from = glm::vec3(1.0f, 2.0f, 3.0f);
  c.at = glm::vec3(0.0f, -1.0f, 0.0f);
  const CameraFrame f = MakeCameraFrame(c, 40, 30);
  const BandWedges w = BandWedges::ForRows(f, 4);
  for (int y = 0; y < 30; ++y) {
    int band = 0;
    while (band < 3 && y >= 30 * (band + 1) / 4) ++band;  // rows [h r / n, h (r + 1) / n)
    for (int x = 0; x < 40; x += 3) {
      const BandWedges::Run run = w.RunOf(PrimaryRay(f, x, y));
      CHECK(run.start == band);
      CHECK(run.hops == 0);
    }
  }
}
