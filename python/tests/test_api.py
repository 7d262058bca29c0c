"""The Python API against known answers: scenes and their properties, rays as the CLI makes them, hits in place
(no copy of the input), normals, occlusion, checks against the fp64 reference, render, errors."""
import math

import numpy as np
import pytest

import cellray

from conftest import ROOT, SPD


def spd(name):
    return cellray.Scene.load(ROOT / f"scenes/spd/{name}.nff")


def test_load_and_properties():
    s = spd("balls")
    assert s.num_prims == 7382  # SPD balls: 7381 spheres and the ground polygon
    assert s.counts["spheres"] == 7381
    lo, hi = s.bounds
    assert all(l < h for l, h in zip(lo, hi))
    assert s.camera["width"] == 512 and s.camera["fov"] == pytest.approx(45.0)
    assert len(s.lights) == 3 and len(s.lights[0]["position"]) == 3
    assert "balls.nff" in repr(s)


def test_load_errors_name_file_and_line(tmp_path):
    bad = tmp_path / "bad.nff"
    bad.write_text("v\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0\nresolution 8 8\ns 0 0 0 banana\n")
    with pytest.raises(ValueError, match=r"bad\.nff:8"):
        cellray.Scene.load(bad)
    with pytest.raises(ValueError, match="cannot open|no such"):
        cellray.Scene.load(tmp_path / "missing.nff")


def test_rays_equal_the_cli(tmp_path, cellray_binary):
    import subprocess
    s = spd("gears")
    for kind, count in (("primary", 0), ("diffuse", 3000), ("shadow", 2000)):
        out = tmp_path / f"{kind}.rays"
        subprocess.run([cellray_binary, "rays", str(ROOT / "scenes/spd/gears.nff"), "--kind", kind, "--size", "40x30",
                        "--count", str(count), "-o", str(out)], check=True, capture_output=True)
        mine = s.rays(kind, width=40, height=30, count=count)
        theirs = cellray.read_rays(out)
        assert mine.dtype == np.float32 and mine.shape[1] == 8
        assert np.array_equal(mine.view(np.uint32), theirs.view(np.uint32)), kind


def test_intersect_traces_the_callers_array_in_place():
    s = spd("tetra")
    rays = s.rays("diffuse", count=5000)
    tracer = s.tracer(accel="grid", backend="simd")
    hits = tracer.intersect(rays)
    # The tracer read the rays where numpy holds them: no copy.
    assert tracer._t._last_input_address == rays.__array_interface__["data"][0]
    # t, prim, u, v are views of one buffer of .hits records.
    recs = hits._records()
    for name, col in (("t", 0), ("prim", 1), ("u", 2), ("v", 3)):
        a = getattr(hits, name)
        assert np.shares_memory(a, recs), name
        assert np.array_equal(a.view(np.uint32), recs[:, col]), name
    assert len(hits) == len(rays)
    assert hits.t.dtype == np.float32 and hits.prim.dtype == np.int32
    miss = hits.prim == -1
    assert miss.any() and (~miss).any()
    assert np.all(np.isinf(hits.t[miss])) and np.all(np.isfinite(hits.t[~miss]))


def test_origins_and_directions():
    s = spd("balls")
    o = np.zeros((4, 3)) + np.array(s.camera["eye"])
    d = np.array(s.camera["at"]) - np.array(s.camera["eye"]) + np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [5, 5, 5]])
    t = s.tracer()
    h = t.intersect(origins=o, directions=d)
    r = cellray.make_rays(o, d)
    assert np.array_equal(h._records(), t.intersect(r)._records())
    h2 = t.intersect(origins=o, directions=d, tmax=1e-3)
    assert np.all(h2.prim == -1)


def test_sphere_normals_and_uv():
    # A unit sphere at the origin and one triangle: normals are (p - c) / r; the triangle reports its barycentrics.
    s = cellray.Scene.from_arrays(vertices=[[3, -1, -1], [3, 1, -1], [3, 0, 1]], triangles=[[0, 1, 2]],
                                  spheres=[[0, 0, 0, 1]])
    assert s.num_prims == 2 and s.counts["triangles"] == 1 and s.counts["spheres"] == 1
    rng = np.random.default_rng(3)
    d = rng.normal(size=(1000, 3))
    o = -5.0 * d / np.linalg.norm(d, axis=1, keepdims=True)
    hits = s.tracer(backend="scalar").intersect(origins=o, directions=-o)
    on = hits.prim == 1  # the rays from +x meet the triangle first
    assert on.sum() > 900 and np.all(hits.prim[~on] == 0)
    p = o[on] + hits.t[on, None] * (-o[on])
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    assert np.max(np.abs(hits.normal[on] - n)) < 1e-5
    tri = s.tracer().intersect(origins=[[2, 0, 0]], directions=[[1, 0, 0]])
    assert tri.prim[0] == 0 and tri.t[0] == pytest.approx(1.0)
    assert tri.u[0] == pytest.approx(0.25) and tri.v[0] == pytest.approx(0.5)
    assert tri.u[0] + tri.v[0] < 1.0 and tri.u[0] > 0 and tri.v[0] > 0
    assert tri.normal[0][0] == pytest.approx(-1.0) or tri.normal[0][0] == pytest.approx(1.0)


def test_occluded_agrees_with_occlusion_hits():
    s = spd("mount")
    rays = s.rays("shadow", count=4000)
    t = s.tracer(accel="octree")
    occ = t.occluded(rays)
    h = t.intersect(rays, occlusion=True)
    assert occ.dtype == np.bool_ and occ.shape == (4000,)
    assert np.array_equal(occ, h.prim != -1)
    assert np.all(h.t[occ] == 0.0)
    assert 0 < occ.sum() < 4000
    assert cellray.check(s, rays, h)["wrong"] == 0


@pytest.mark.parametrize("accel", ["grid", "octree", "bvh", "hgrid"])
def test_check_zero_wrong_and_stats(accel):
    s = spd("teapot")
    rays = s.rays("diffuse", count=6000)
    t = s.tracer(accel=accel, backend="simd", stats=True)
    hits = t.intersect(rays)
    c = cellray.check(s, rays, hits)
    assert c["rays"] == 6000 and c["wrong"] == 0 and c["agree"] > 5000
    st = t.stats()
    assert st["rays"] == 6000 and st["build_ms"] > 0 and st["bytes"] > 0
    assert st["intersection_tests"] > 0 and st["traversal_steps"] > 0
    # A wrong answer is seen: every hit moved to another primitive.
    bad = hits.records().copy()
    hit = bad["prim"] >= 0
    bad["prim"][hit] = (bad["prim"][hit] + 1) % s.num_prims
    assert cellray.check(s, rays, bad)["wrong"] > 1000


def test_structure_parameters():
    s = spd("rings")
    a = s.tracer(accel="grid", grid_density=1).stats()
    b = s.tracer(accel="grid", grid_density=8).stats()
    assert a["nodes"] < b["nodes"]
    with pytest.raises(TypeError, match="unexpected keyword argument 'grid_desnity'"):
        s.tracer(accel="grid", grid_desnity=2)


def test_bad_arguments_raise_clear_errors():
    s = spd("tetra")
    t = s.tracer()
    rays = s.rays("random", count=10)
    with pytest.raises(TypeError, match="float32"):
        t.intersect(rays.astype(np.float64))
    with pytest.raises(ValueError, match=r"\(N, 8\)"):
        t.intersect(rays[:, :7].copy())
    with pytest.raises(TypeError, match="C-contiguous"):
        t.intersect(np.asfortranarray(rays))
    with pytest.raises(TypeError, match="numpy.ndarray"):
        t.intersect(rays.tolist())
    nan = rays.copy()
    nan[3, 4] = np.nan
    with pytest.raises(ValueError, match=r"rays\[3\]: NaN"):
        t.intersect(nan)
    back = rays.copy()
    back[2, 3] = 5.0
    back[2, 7] = 1.0
    with pytest.raises(ValueError, match=r"rays\[2\]: tmin 5 > tmax 1"):
        t.intersect(back)
    with pytest.raises(ValueError, match="accel"):
        s.tracer(accel="kdtree")
    with pytest.raises(ValueError, match="backend"):
        s.tracer(backend="cuda")
    with pytest.raises(ValueError, match="shutter"):
        t.intersect(rays, times=np.full(10, 2.0))
    with pytest.raises(ValueError, match="vertex index"):
        cellray.Scene.from_arrays([[0, 0, 0]], [[0, 1, 2]])
    with pytest.raises(TypeError, match="grid_density': expected a number"):
        s.tracer(accel="grid", grid_density="x")
    with pytest.raises(ValueError, match="grid_density' = -1"):
        s.tracer(accel="grid", grid_density=-1)
    with pytest.raises(ValueError, match="count -1 is negative"):
        s.rays("random", count=-1)
    with pytest.raises(ValueError, match="width -5"):
        s.rays("primary", width=-5, height=3)
    with pytest.raises(ValueError, match="size"):
        s.render(size=(-3, 4))
    with pytest.raises(ValueError, match="--spp 0"):
        s.render(size=(4, 4), spp=0)


def test_motion_rays_with_times():
    s = cellray.Scene.load(ROOT / "scenes/distributed/motion.nff")
    assert s.has_motion
    rays, times = s.rays("diffuse", count=3000, return_times=True)
    assert times.shape == (3000,) and times.max() > 0.5
    t = s.tracer(accel="bvh")
    h = t.intersect(rays, times=times)
    assert cellray.check(s, rays, h, times=times)["wrong"] == 0
    # Without the times, the moving pieces are answered at time 0: the checker sees it.
    h0 = t.intersect(rays)
    assert cellray.check(s, rays, h0, times=times)["wrong"] > 20


def test_render_matches_the_cli(tmp_path, cellray_binary):
    import subprocess
    s = spd("balls")
    img = s.render(size=(48, 32), backend="simd", spp=2)
    assert img.shape == (32, 48, 3) and img.dtype == np.float32
    assert img.mean() > 0.05
    exr = tmp_path / "b.exr"
    subprocess.run([cellray_binary, "render", str(ROOT / "scenes/spd/balls.nff"), "--size", "48x32", "--spp", "2",
                    "--backend", "simd", "--no-progress", "-o", str(exr)], check=True, capture_output=True)
    assert np.array_equal(cellray.read_image(exr), img)  # the same image, bit for bit
    cellray.write_image(tmp_path / "mine.exr", img)
    assert np.array_equal(cellray.read_image(tmp_path / "mine.exr"), img)


def test_read_write_round_trip(tmp_path):
    s = spd("tetra")
    rays = s.rays("random", count=100)
    cellray.write_rays(tmp_path / "r.rays", rays)
    assert np.array_equal(cellray.read_rays(tmp_path / "r.rays"), rays)
    h = s.tracer().intersect(rays)
    cellray.write_hits(tmp_path / "h.hits", h)
    back = cellray.read_hits(tmp_path / "h.hits")
    assert back.dtype == cellray.HIT_DTYPE
    assert np.array_equal(back.view(np.uint32), h._records().reshape(-1))


def test_every_kind_of_bad_ray_is_found_anywhere():
    # The check runs block by block (a quick vector test, then the exact rule): each kind of bad ray, alone in a
    # large set at a block's edge or inside one, is named by its row.
    s = spd("tetra")
    t = s.tracer()
    good = s.rays("random", count=70000)
    t.intersect(good)  # all valid
    cases = {"NaN": (4, np.nan), "infinite origin": (0, np.inf), "infinite direction": (6, -np.inf),
             "zero direction": (None, 0.0), "tmin": (3, -1.0), "infinite tmin": (3, np.inf), "NaN in tmax": (7, np.nan)}
    for why, (col, value) in cases.items():
        for row in (0, 16383, 16384, 40000, 69999):
            bad = good.copy()
            if col is None:
                bad[row, 4:7] = 0.0
            else:
                bad[row, col] = value
            with pytest.raises(ValueError, match=rf"rays\[{row}\]"):
                t.intersect(bad)
    bad = good.copy()
    bad[123, 3], bad[123, 7] = 2.0, 1.0
    with pytest.raises(ValueError, match=r"rays\[123\]: tmin 2 > tmax 1"):
        t.intersect(bad)
    ok = good.copy()
    ok[5, 7] = np.inf
    ok[6, 3] = -0.0
    t.intersect(ok)  # tmax = inf and tmin = -0 are allowed, as the .rays reader allows them
