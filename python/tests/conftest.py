"""Shared fixtures: the repository root and the cellray binary the CLI comparisons run (CELLRAY_BINARY, set by
ctest; else build/release/bin/cellray)."""
import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SPD = ["balls", "gears", "mount", "rings", "teapot", "tetra", "tree"]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def cellray_binary():
    b = os.environ.get("CELLRAY_BINARY") or str(ROOT / "build" / "release" / "bin" / "cellray")
    if not os.path.exists(b):
        pytest.skip(f"no cellray binary at {b}")
    return b


def have_opencl():
    import cellray
    try:
        cellray.Scene.load(str(ROOT / "scenes/spd/tetra.nff")).tracer(backend="opencl")
        return True
    except RuntimeError:
        return False
