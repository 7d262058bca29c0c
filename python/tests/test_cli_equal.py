"""Answers from Python equal the CLI's .hits bit for bit: every SPD scene x structure x backend (closest hits on
primary and diffuse rays; any-hit on shadow rays with the BVH), the same ray files traced both ways."""
import subprocess

import numpy as np
import pytest

import cellray

from conftest import ROOT, SPD, have_opencl

ACCELS = ["grid", "octree", "bvh", "hgrid"]
BACKENDS = ["scalar", "simd"] + (["opencl"] if have_opencl() else [])


@pytest.fixture(scope="module")
def ray_files(tmp_path_factory, cellray_binary):
    d = tmp_path_factory.mktemp("rays")
    files = {}
    for name in SPD:
        scene = str(ROOT / f"scenes/spd/{name}.nff")
        closest = d / f"{name}.rays"
        shadow = d / f"{name}_shadow.rays"
        s = cellray.Scene.load(scene)
        # Primary rays of a 48 x 32 image, then diffuse rays: one closest-hit set.
        rays = np.concatenate([s.rays("primary", width=48, height=32), s.rays("diffuse", count=2500)])
        cellray.write_rays(closest, rays)
        subprocess.run([cellray_binary, "rays", scene, "--kind", "shadow", "--count", "2500", "-o", str(shadow)],
                       check=True, capture_output=True)
        files[name] = (s, closest, shadow)
    return files


def cli_hits(binary, scene, rays, out, accel, backend, occlusion=False):
    cmd = [binary, "trace", str(ROOT / f"scenes/spd/{scene}.nff"), "--rays", str(rays), "--accel", accel, "--backend",
           backend, "-o", str(out)] + (["--occlusion"] if occlusion else [])
    subprocess.run(cmd, check=True, capture_output=True)
    return cellray.read_hits(out)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("accel", ACCELS)
@pytest.mark.parametrize("name", SPD)
def test_closest_hits_equal_the_cli(ray_files, cellray_binary, tmp_path, name, accel, backend):
    s, closest, _ = ray_files[name]
    rays = cellray.read_rays(closest)
    theirs = cli_hits(cellray_binary, name, closest, tmp_path / "c.hits", accel, backend)
    mine = s.tracer(accel=accel, backend=backend).intersect(rays)
    assert np.array_equal(mine.records().view(np.uint32), theirs.view(np.uint32))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", SPD)
def test_shadow_hits_equal_the_cli(ray_files, cellray_binary, tmp_path, name, backend):
    s, _, shadow = ray_files[name]
    rays = cellray.read_rays(shadow)
    theirs = cli_hits(cellray_binary, name, shadow, tmp_path / "s.hits", "bvh", backend, occlusion=True)
    mine = s.tracer(accel="bvh", backend=backend).intersect(rays, occlusion=True)
    assert np.array_equal(mine.records().view(np.uint32), theirs.view(np.uint32))
