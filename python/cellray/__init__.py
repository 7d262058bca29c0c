"""cellray: choose a spatial structure, a backend and a precision, trace numpy
rays, and judge the answers against an exact fp64 reference.

    import numpy as np, cellray
    scene = cellray.Scene.load("scenes/spd/balls.nff")
    rays = scene.rays("diffuse", count=100_000)          # (N, 8) float32, the .rays layout
    tracer = scene.tracer(accel="grid", backend="simd")
    hits = tracer.intersect(rays)                         # hits.t, hits.prim, hits.u, hits.v, hits.normal
    print(cellray.check(scene, rays, hits))               # {'agree': ..., 'wrong': 0, ...}

The whole API, with examples that run as written: docs/PYTHON.md.
"""
from __future__ import annotations

import numpy as _np

from . import _cellray

__all__ = ["Scene", "Tracer", "Hits", "check", "read_rays", "write_rays", "read_hits", "write_hits", "read_image",
           "write_image",
           "RAY_FIELDS", "HIT_DTYPE"]
__version__ = "0.22.0"

#: The columns of a ray array: one .rays record (../shared/FORMATS.md) per row.
RAY_FIELDS = ("ox", "oy", "oz", "tmin", "dx", "dy", "dz", "tmax")
#: The .hits record as a numpy structured dtype (prim is -1 on a miss).
HIT_DTYPE = _np.dtype([("t", "<f4"), ("prim", "<i4"), ("u", "<f4"), ("v", "<f4")])

Hits = _cellray.Hits
Hits.__doc__ = """The answers of one Tracer.intersect call, one per ray.

    t       (N,) float32: distance along the ray (inf on a miss; 0 for an occlusion query's hit)
    prim    (N,) int32: primitive id (the scene file's statement, FORMATS.md), -1 on a miss
    u, v    (N,) float32: barycentrics on whole-triangle statements, else 0
    normal  (N, 3) float32: outward geometric normal at the hit (0 on a miss), computed on first use
            from the rays array passed to intersect (do not modify it before)
    occlusion: whether these are occlusion answers
    records(): (N,) structured array of HIT_DTYPE (a copy), the .hits file's records

t, prim, u and v are views of the buffer the tracer wrote (no copy)."""


def _records(hits):
    return hits._records().view(HIT_DTYPE).reshape(-1)


Hits.records = _records


def _ray_array(rays, name="rays"):
    """The rays as the (N, 8) float32 C-contiguous array the tracers read in place."""
    if not isinstance(rays, _np.ndarray):
        raise TypeError(f"{name}: expected a numpy.ndarray of shape (N, 8) and dtype float32, got {type(rays).__name__}")
    if rays.dtype != _np.float32:
        raise TypeError(f"{name}: dtype {rays.dtype}, expected float32 (the .rays record layout; convert with "
                        f"{name}.astype(numpy.float32))")
    if rays.ndim != 2 or rays.shape[1] != 8:
        raise ValueError(f"{name}: shape {rays.shape}, expected (N, 8): ox oy oz tmin dx dy dz tmax per row")
    if not rays.flags["C_CONTIGUOUS"]:
        raise TypeError(f"{name}: not C-contiguous (numpy.ascontiguousarray({name}) makes it so)")
    _cellray._validate_rays(rays)
    return rays


def _time_array(times, n):
    if times is None:
        return None
    times = _np.ascontiguousarray(times, dtype=_np.float32)
    if times.shape != (n,):
        raise ValueError(f"times: shape {times.shape}, expected ({n},): one shutter time per ray")
    if not _np.all((times >= 0.0) & (times <= 1.0)):
        bad = int(_np.flatnonzero(~((times >= 0.0) & (times <= 1.0)))[0])
        raise ValueError(f"times[{bad}] = {times[bad]} is not in the shutter interval [0, 1]")
    return times


def make_rays(origins, directions, tmin=0.0, tmax=_np.inf):
    """An (N, 8) float32 ray array from (N, 3) origins and directions (and a tmin, tmax each or per ray)."""
    o = _np.asarray(origins, dtype=_np.float32)
    d = _np.asarray(directions, dtype=_np.float32)
    if o.ndim != 2 or o.shape[1] != 3:
        raise ValueError(f"origins: shape {o.shape}, expected (N, 3)")
    if d.shape != o.shape:
        raise ValueError(f"directions: shape {d.shape}, expected {o.shape} (one per origin)")
    r = _np.empty((o.shape[0], 8), dtype=_np.float32)
    r[:, 0:3] = o
    r[:, 3] = tmin
    r[:, 4:7] = d
    r[:, 7] = tmax
    return r


__all__.append("make_rays")


def _rays_given(call, rays, origins, directions, tmin, tmax):
    """The checked (N, 8) array of a call given rays, or origins and directions."""
    if rays is None:
        if origins is None or directions is None:
            raise TypeError(f"{call}: give rays (N, 8) or origins and directions (N, 3)")
        rays = make_rays(origins, directions, tmin, tmax)
    elif origins is not None or directions is not None:
        raise TypeError(f"{call}: give rays or origins and directions, not both")
    return _ray_array(rays)


class Scene:
    """A scene: primitives, materials, camera and lights."""

    def __init__(self, native):
        self._s = native

    @staticmethod
    def load(path) -> "Scene":
        """Loads .nff (with cellray's extensions) or .obj with its .view file. ValueError names file:line."""
        return Scene(_cellray.Scene.load(str(path)))

    @staticmethod
    def from_arrays(vertices, triangles, spheres=None, camera=None, lights=None) -> "Scene":
        """A scene of triangles (vertex indices into vertices, (T, 3)) and spheres ((S, 4): x y z radius).
        Primitive ids: the triangles 0..T-1, then the spheres. camera: a dict with eye, at, up, fov
        (degrees), width, height; lights: a list of (position, colour) pairs."""
        v = _np.ascontiguousarray(vertices, dtype=_np.float64)
        t = _np.ascontiguousarray(triangles, dtype=_np.int64)
        s = _np.ascontiguousarray(_np.zeros((0, 4)) if spheres is None else spheres, dtype=_np.float64)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices: shape {v.shape}, expected (V, 3)")
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"triangles: shape {t.shape}, expected (T, 3) vertex indices")
        if s.ndim != 2 or s.shape[1] != 4:
            raise ValueError(f"spheres: shape {s.shape}, expected (S, 4): x y z radius")
        if not (_np.all(_np.isfinite(v)) and _np.all(_np.isfinite(s))):
            raise ValueError("vertices and spheres must be finite")
        scene = Scene(_cellray.Scene.from_arrays(v, t, s))
        if camera is not None:
            c = dict(camera)
            scene._s._set_camera(list(c.get("eye", (0, 0, 1))), list(c.get("at", (0, 0, 0))),
                                 list(c.get("up", (0, 1, 0))), float(c.get("fov", 45.0)),
                                 int(c.get("width", 512)), int(c.get("height", 512)))
        for p, col in (lights or []):
            scene._s._add_light(list(map(float, p)), list(map(float, col)))
        return scene

    path = property(lambda self: self._s.path, doc="The file it was loaded from")
    num_prims = property(lambda self: self._s.num_prims, doc="Primitive ids (geometry statements)")
    num_pieces = property(lambda self: self._s.num_pieces,
                          doc="Pieces the structures hold (polygons split into triangles)")
    counts = property(lambda self: self._s.counts, doc="Pieces per primitive type")
    bounds = property(lambda self: self._s.bounds, doc="(lo, hi) corners of all geometry")
    camera = property(lambda self: self._s.camera, doc="The camera (eye, at, up, fov, width, height, lens)")
    lights = property(lambda self: self._s.lights, doc="Point lights (position, color)")
    has_motion = property(lambda self: self._s.has_motion, doc="Whether some primitive moves (NFF motion)")

    def __repr__(self):
        return f"cellray.Scene({self.path!r}, {self.num_prims} primitives, {self.num_pieces} pieces)"

    def tracer(self, accel="bvh", backend="simd", precision="robust", device=None, threads=0, variant=None,
               isa=None, stats=False, **structure_params) -> "Tracer":
        """Builds a structure (grid, octree, bvh, hgrid) for a backend (reference, scalar, simd, opencl, embree,
        auto) at a precision (fast, robust, fp64). structure_params: grid_density, octree_leaf, octree_depth,
        octree_build, octree_mailbox, octree_margin, octree_root, octree_leaf_box, bvh_leaf, bvh_quality, bvh_sah_block, hgrid_top_density,
        hgrid_density, hgrid_leaf, hgrid_skip (the CLI's options).
        stats=True gathers Havran's per-ray measures over the calls (Tracer.stats())."""
        return Tracer(_cellray.Tracer(self._s, accel, backend, precision, device, int(threads), variant, isa,
                                      bool(stats), structure_params))

    def rays(self, kind="primary", width=0, height=0, spd_corners=False, seed=1, count=0, return_times=False):
        """The rays `cellray rays` writes: primary (through the pixel centres, or the corners), shadow, diffuse,
        random, soft. width, height: the image (0: the camera's); count: secondary rays (0: width x height).
        Returns an (N, 8) float32 array; with return_times, (rays, times) (a moving scene's shutter times)."""
        for name, v in (("width", width), ("height", height), ("count", count), ("seed", seed)):
            if int(v) < 0:
                raise ValueError(f"rays: {name} {v} is negative")
        r, t = self._s._rays(kind, int(width), int(height), bool(spd_corners), int(seed), int(count))
        return (r, t) if return_times else r

    def render(self, size=None, spp=1, integrator="whitted", depth=None, spd=False, seed=1, diffuse=None,
               area_lights=0.0, fresnel=False, sides="auto", accel="bvh", backend="simd", precision="robust",
               threads=0):
        """Renders as `cellray render` does; returns an (H, W, 3) float32 linear image."""
        w, h = (0, 0) if size is None else (int(size[0]), int(size[1]))
        if size is not None and (w < 1 or h < 1 or w > 65536 or h > 65536):
            raise ValueError(f"render: size {size} is not (W, H) with W and H in 1..65536")
        if int(seed) < 0 or int(threads) < 0 or float(area_lights) < 0.0:
            raise ValueError("render: seed, threads and area_lights must be >= 0")
        return self._s._render(accel, backend, precision, int(threads), int(w), int(h), int(spp), integrator,
                               int(depth or 0), bool(spd), int(seed), diffuse or "", float(area_lights),
                               bool(fresnel), sides)


class Tracer:
    """A structure built for one backend over one scene."""

    def __init__(self, native):
        self._t = native

    backend = property(lambda self: self._t.backend, doc="The backend answering (simd once auto fell back)")
    accel = property(lambda self: self._t.accel)
    precision = property(lambda self: self._t.precision)
    device = property(lambda self: self._t.device)
    variant = property(lambda self: self._t.variant)

    def __repr__(self):
        return f"cellray.Tracer({self.accel}, {self.backend}, {self.precision})"

    def intersect(self, rays=None, *, origins=None, directions=None, tmin=0.0, tmax=_np.inf, times=None,
                  occlusion=False, out=None) -> Hits:
        """Closest hits (occlusion=True: any hit, t = 0 and a blocker's id) of an (N, 8) float32 ray array,
        traced in place, or of origins and directions (N, 3). The GIL is released while tracing.
        out: a Hits of an earlier call with as many rays, written over and returned (no new memory: its
        arrays, and views of them, then hold the new answers)."""
        rays = _rays_given("intersect", rays, origins, directions, tmin, tmax)
        if out is not None:
            if not isinstance(out, Hits):
                raise TypeError(f"out: expected a cellray.Hits, got {type(out).__name__}")
            self._t._trace_into(rays, _time_array(times, rays.shape[0]), bool(occlusion), out)
            return out
        return self._t._trace(rays, _time_array(times, rays.shape[0]), bool(occlusion))

    def occluded(self, rays=None, *, origins=None, directions=None, tmin=0.0, tmax=_np.inf, times=None):
        """Whether each ray is blocked in [tmin, tmax]: an (N,) bool array."""
        rays = _rays_given("occluded", rays, origins, directions, tmin, tmax)
        return self._t._occluded(rays, _time_array(times, rays.shape[0]))

    def stats(self) -> dict:
        """Build time (ms), bytes, nodes, leaves, empty leaves, references, parameters; with stats=True, the rays
        traced and Havran's per-ray measures (intersection tests, traversal steps, leaves, empty leaves)."""
        return self._t.stats()


def check(scene: Scene, rays, hits, times=None) -> dict:
    """Judges hits (a Hits, or a HIT_DTYPE array with occlusion taken as False) against the fp64 reference, ray by
    ray (`cellray check`): agree, ties, flips, wrong (missed, farther, not on the primitive), t errors."""
    rays = _ray_array(rays)
    occlusion = False
    if isinstance(hits, Hits):
        occlusion = hits.occlusion
        recs = hits._records()
    else:
        recs = _np.ascontiguousarray(_np.asarray(hits).view(_np.uint32).reshape(-1, 4))
    return _cellray._check(scene._s, rays, _time_array(times, rays.shape[0]), recs, occlusion)


def read_rays(path, return_times=False):
    """A .rays file (CRRAYS01 or CRRAYS02) as an (N, 8) float32 array (and its times)."""
    r, t = _cellray._read_rays(str(path))
    return (r, t) if return_times else r


def write_rays(path, rays, times=None):
    """Writes a .rays file (CRRAYS02 when times are given and not all 0)."""
    rays = _ray_array(rays)
    _cellray._write_rays(str(path), rays, _time_array(times, rays.shape[0]))


def read_hits(path):
    """A .hits file as an (N,) array of HIT_DTYPE."""
    return _cellray._read_hits(str(path)).view(HIT_DTYPE).reshape(-1)


def write_hits(path, hits):
    """Writes a .hits file from a Hits or a HIT_DTYPE array."""
    recs = hits._records() if isinstance(hits, Hits) else _np.ascontiguousarray(_np.asarray(hits).view(_np.uint32).reshape(-1, 4))
    _cellray._write_hits(str(path), _np.ascontiguousarray(recs))


def read_image(path):
    """An image file (EXR, PNG, ... through OpenImageIO) as an (H, W, 3) float32 array (linear for EXR)."""
    return _cellray._read_image(str(path))


def write_image(path, image):
    """Writes an (H, W, 3) image as the CLI writes its renders: .exr float linear, .png 8-bit sRGB."""
    img = _np.ascontiguousarray(image, dtype=_np.float32)
    if img.ndim != 3 or img.shape[2] != 3:
        raise ValueError(f"image: shape {img.shape}, expected (H, W, 3)")
    _cellray._write_image(str(path), img)
