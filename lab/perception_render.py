"""A small ray-caster that makes camera images of scenes whose geometry is known exactly.

It is the truth the perception wing (:mod:`planner.perception`, paper 001 §3.2–3.3) is checked against: the
tests, the benchmark (``sphereplan bench --suite perception``) and the docs' example pair are rendered here.
It shares no code with the planner's camera model: poses are built with :class:`scipy.spatial.transform.Rotation`
from the physical description (a camera on the sphere's main axis, the axis tipped sideways by the lean), rays
are cast in NumPy against infinite planes and axis-aligned boxes, and the picture is a solid (3-D) value-noise
texture evaluated where each ray lands, so both cameras of a pair see the same surface pattern.

Conventions: the map frame is REP-103 (x forward at yaw 0, y left, z up, metres); a camera's optical frame is
ROS's (x right, y down, z forward); pixel ``(u, v)`` has its centre at integer coordinates (OpenCV's
convention), so a point at optical ``(X, Y, Z)`` lands at ``u = fx X / Z + cx``, ``v = fy Y / Z + cy``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

#: the optical axes (x right, y down, z forward) written in a body frame that looks along its own x
_OPTICAL_IN_BODY = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
SKY = 235.0  # grey level where a ray hits nothing


@dataclass(frozen=True)
class Pinhole:
    """A pinhole camera: ``width`` × ``height`` pixels, focal lengths and principal point in pixels, and its
    pose in the map (``rotation`` (3, 3): optical axes as columns in the map frame; ``position`` (3,), m)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    rotation: np.ndarray
    position: np.ndarray

    def project(self, points_map: np.ndarray) -> np.ndarray:
        """Pixel coordinates (N, 2) of map points (N, 3) (in front of the camera or not: no clipping)."""
        p = (np.asarray(points_map, float) - self.position) @ self.rotation
        return np.stack([self.fx * p[:, 0] / p[:, 2] + self.cx, self.fy * p[:, 1] / p[:, 2] + self.cy], axis=1)


def intrinsics(width: int, height: int, hfov_deg: float) -> tuple[float, float, float, float]:
    """(fx, fy, cx, cy) of a square-pixel camera with horizontal field of view ``hfov_deg``, centred."""
    f = 0.5 * width / math.tan(math.radians(hfov_deg) / 2)
    return f, f, (width - 1) / 2, (height - 1) / 2


def body_attitude(yaw_rad: float, lean_left_rad: float = 0.0, pitch_rad: float = 0.0) -> Rotation:
    """The attitude of the sphere's main axis: heading ``yaw_rad`` about the vertical, the axis tipped so that the
    top leans left by ``lean_left_rad`` (sphereplan's roll, > 0 leans and turns left) and nose-down by
    ``pitch_rad`` (REP-103 pitch, > 0 nose down), applied in the body's own axes: yaw, then pitch, then lean."""
    turn = Rotation.from_rotvec([0.0, 0.0, yaw_rad])
    nod = Rotation.from_rotvec([0.0, pitch_rad, 0.0])
    lean = Rotation.from_rotvec([-lean_left_rad, 0.0, 0.0])  # top toward +y: a negative turn about forward x
    return turn * nod * lean


def camera_on_sphere(width: int, height: int, hfov_deg: float, x: float, y: float, yaw_rad: float,
                     radius_m: float, offset_left_m: float, lean_left_rad: float = 0.0,
                     pitch_rad: float = 0.0) -> Pinhole:
    """A camera on the main axis, ``offset_left_m`` to the left of the sphere's centre (r above the ground),
    looking forward, turning with the body (:func:`body_attitude`)."""
    att = body_attitude(yaw_rad, lean_left_rad, pitch_rad)
    centre = np.array([x, y, radius_m])
    position = centre + att.apply([0.0, offset_left_m, 0.0])
    fx, fy, cx, cy = intrinsics(width, height, hfov_deg)
    return Pinhole(width, height, fx, fy, cx, cy, att.as_matrix() @ _OPTICAL_IN_BODY, position)


def camera_with_attitude(width: int, height: int, hfov_deg: float, position: Sequence[float],
                         roll_rad: float, pitch_rad: float, yaw_rad: float = 0.0) -> Pinhole:
    """A camera whose body (x forward, y left, z up) has the REP-103 attitude roll, pitch, yaw (intrinsic
    Z-Y'-X'': yaw, then pitch, then roll) at ``position``: what an IMU on it would report."""
    att = Rotation.from_euler("ZYX", [yaw_rad, pitch_rad, roll_rad])
    fx, fy, cx, cy = intrinsics(width, height, hfov_deg)
    return Pinhole(width, height, fx, fy, cx, cy, att.as_matrix() @ _OPTICAL_IN_BODY,
                   np.asarray(position, float))


# --------------------------------------------------------------------------------------------- texture


def _lattice(ix: np.ndarray, iy: np.ndarray, iz: np.ndarray, seed: int) -> np.ndarray:
    """A pseudo-random value in [0, 1) per integer lattice point (integer hash, wraps in uint64)."""
    with np.errstate(over="ignore"):
        h = (ix.astype(np.uint64) * np.uint64(0x9E3779B1) ^ iy.astype(np.uint64) * np.uint64(0x85EBCA77)
             ^ iz.astype(np.uint64) * np.uint64(0xC2B2AE3D) ^ np.uint64(seed * 0x27D4EB2F + 0x165667B1))
        h ^= h >> np.uint64(15)
        h *= np.uint64(0x2C1B3C6D)
        h ^= h >> np.uint64(12)
        h *= np.uint64(0x297A2D39)
        h ^= h >> np.uint64(15)
    return (h & np.uint64(0xFFFFFF)).astype(float) / float(0x1000000)


def value_noise(points: np.ndarray, cell_m: float, seed: int) -> np.ndarray:
    """Smooth solid noise in [0, 1] at map points (N, 3): lattice values ``cell_m`` apart, blended trilinearly
    with a smoothstep."""
    q = points / cell_m
    base = np.floor(q)
    f = q - base
    f = f * f * (3 - 2 * f)
    i = base.astype(np.int64)
    out = np.zeros(len(points))
    for dx in (0, 1):
        wx = f[:, 0] if dx else 1 - f[:, 0]
        for dy in (0, 1):
            wy = f[:, 1] if dy else 1 - f[:, 1]
            for dz in (0, 1):
                wz = f[:, 2] if dz else 1 - f[:, 2]
                out += wx * wy * wz * _lattice(i[:, 0] + dx, i[:, 1] + dy, i[:, 2] + dz, seed)
    return out


def texture(points: np.ndarray, seed: int, scale_m: float = 1.0) -> np.ndarray:
    """Grey levels (N,) in [25, 230] of a three-octave solid texture (cells 0.4, 0.12, 0.04 m × ``scale_m``)."""
    n = (0.45 * value_noise(points, 0.4 * scale_m, seed) + 0.35 * value_noise(points, 0.12 * scale_m, seed + 1)
         + 0.20 * value_noise(points, 0.04 * scale_m, seed + 2))
    return 25.0 + 205.0 * np.clip((n - 0.5) * 1.8 + 0.5, 0.0, 1.0)


# ---------------------------------------------------------------------------------------------- scene


@dataclass(frozen=True)
class Plane:
    """The infinite plane through ``point`` with normal ``normal``."""

    name: str
    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    seed: int = 1
    texture_scale: float = 1.0

    def hit(self, origin: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        n = np.asarray(self.normal, float)
        den = dirs @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((np.asarray(self.point, float) - origin) @ n) / den
        return np.where((np.abs(den) > 1e-12) & (t > 1e-9), t, np.inf)


@dataclass(frozen=True)
class Box:
    """The axis-aligned box ``lo`` ≤ p ≤ ``hi`` (map frame, m)."""

    name: str
    lo: tuple[float, float, float]
    hi: tuple[float, float, float]
    seed: int = 2
    texture_scale: float = 1.0

    def hit(self, origin: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        lo, hi = np.asarray(self.lo, float), np.asarray(self.hi, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / dirs
            t1, t2 = (lo - origin) * inv, (hi - origin) * inv
        t1 = np.where(np.isnan(t1), -np.inf, t1)
        t2 = np.where(np.isnan(t2), np.inf, t2)
        near = np.minimum(t1, t2).max(axis=1)
        far = np.maximum(t1, t2).min(axis=1)
        return np.where((near <= far) & (near > 1e-9), near, np.inf)


@dataclass(frozen=True)
class Scene:
    """Objects the rays can hit; a ray that hits none sees the sky (grey :data:`SKY`). The objects are given in the
    scene's own frame, which stands in the map at ``pose`` (x, y, yaw: turned about the vertical, then moved), so
    one course can be put in front of a sphere anywhere."""

    objects: tuple[Plane | Box, ...]
    sky: float = SKY
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def placed(self, x: float, y: float, yaw_rad: float) -> Scene:
        """The same scene standing at (x, y) turned by ``yaw_rad``."""
        return Scene(self.objects, self.sky, (x, y, yaw_rad))

    def to_local(self, points_map: np.ndarray) -> np.ndarray:
        """Map points (N, 3) in the scene's own frame."""
        x, y, yaw = self.pose
        return (np.asarray(points_map, float) - [x, y, 0.0]) @ Rotation.from_rotvec([0, 0, yaw]).as_matrix()


@dataclass(frozen=True)
class Render:
    """A rendered frame: ``image`` (H, W) uint8; ``depth`` (H, W) optical-axis depth Z of the pixel centre's ray
    (m, inf for sky); ``hit`` (H, W) index into the scene's objects (−1: sky); ``points`` (H, W, 3) where the
    pixel centre's ray lands (map frame, m; NaN for sky)."""

    image: np.ndarray
    depth: np.ndarray
    hit: np.ndarray
    points: np.ndarray = field(repr=False)


def _cast(camera: Pinhole, scene: Scene, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, ...]:
    """(grey, depth, object index, landing point) of the rays through pixel coordinates ``u``, ``v`` (N,)."""
    d_opt = np.stack([(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, np.ones_like(u)], axis=1)
    dirs = d_opt @ camera.rotation.T
    turn = Rotation.from_rotvec([0, 0, scene.pose[2]]).as_matrix()
    origin_local, dirs_local = scene.to_local(camera.position[None])[0], dirs @ turn  # a rigid motion keeps t
    ts = np.stack([obj.hit(origin_local, dirs_local) for obj in scene.objects], axis=1)
    which = np.argmin(ts, axis=1)
    t = ts[np.arange(len(u)), which]
    sky = ~np.isfinite(t)
    which = np.where(sky, -1, which)
    points = camera.position + dirs * np.where(sky, np.nan, t)[:, None]
    local = origin_local + dirs_local * np.where(sky, np.nan, t)[:, None]
    grey = np.full(len(u), scene.sky)
    for k, obj in enumerate(scene.objects):
        sel = which == k
        if sel.any():
            grey[sel] = texture(local[sel], obj.seed, obj.texture_scale)  # the texture moves with the scene
    return grey, np.where(sky, np.inf, t), which, points  # t along d_opt (z = 1) is the optical depth


def render(camera: Pinhole, scene: Scene, supersample: int = 2, rows_per_chunk: int = 64) -> Render:
    """Ray-cast ``scene`` through ``camera``: each pixel averages ``supersample``² rays spread over its area (an
    antialiased picture); depth, object and landing point are those of the ray through the pixel centre."""
    h, w = camera.height, camera.width
    image = np.empty((h, w))
    depth = np.empty((h, w))
    hit = np.empty((h, w), dtype=int)
    points = np.empty((h, w, 3))
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    us = np.arange(w, dtype=float)
    for r0 in range(0, h, rows_per_chunk):
        rows = np.arange(r0, min(h, r0 + rows_per_chunk), dtype=float)
        vv, uu = np.meshgrid(rows, us, indexing="ij")
        _, d, k, p = _cast(camera, scene, uu.ravel(), vv.ravel())
        depth[r0:r0 + len(rows)] = d.reshape(len(rows), w)
        hit[r0:r0 + len(rows)] = k.reshape(len(rows), w)
        points[r0:r0 + len(rows)] = p.reshape(len(rows), w, 3)
        acc = np.zeros(len(rows) * w)
        for oy in offsets:
            for ox in offsets:
                acc += _cast(camera, scene, uu.ravel() + ox, vv.ravel() + oy)[0]
        image[r0:r0 + len(rows)] = (acc / supersample**2).reshape(len(rows), w)
    return Render(np.clip(np.rint(image), 0, 255).astype(np.uint8), depth, hit, points)


# --------------------------------------------------------------------------------------------- scenes

#: the obstacle course of the stereo checks (robot at the origin looking along +x)
BOX_AHEAD = Box("box 9 m ahead", (9.0, -0.8, 0.0), (9.6, 0.8, 0.8), seed=11)
BAR_ABOVE = Box("bar suspended above the robot", (5.0, -2.5, 1.3), (5.15, 2.5, 1.45), seed=21)
WALL_FAR = Box("wall 14 m ahead", (14.0, -25.0, 0.0), (14.3, 25.0, 14.0), seed=31)
BOX_BEHIND = Box("box behind the cameras", (-3.0, -1.0, 0.0), (-2.5, 1.0, 1.0), seed=41)
GROUND = Plane("ground", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), seed=51, texture_scale=3.0)


def obstacle_course() -> Scene:
    """The ground, a box 9 m ahead (1.6 m wide, 0.8 m tall), a bar 1.3–1.45 m above the ground 5 m ahead, a wall
    14 m ahead that fills the background, and a box behind the cameras."""
    return Scene((GROUND, BOX_AHEAD, BAR_ABOVE, WALL_FAR, BOX_BEHIND))


def horizon_scene() -> Scene:
    """A textured ground to the horizon under a plain sky, with boxes to the front and sides: a level camera at
    height h sees the horizon as the straight row v = cy."""
    boxes = (Box("box a", (6.0, -3.0, 0.0), (7.0, -1.5, 1.6), seed=61),
             Box("box b", (8.0, 1.0, 0.0), (9.0, 2.5, 2.4), seed=62),
             Box("box c", (4.0, 2.5, 0.0), (4.6, 3.4, 0.9), seed=63),
             Box("box d", (11.0, -1.0, 0.0), (12.0, 0.5, 3.0), seed=64))
    return Scene((Plane("ground", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), seed=71, texture_scale=2.0), *boxes))


# ------------------------------------------------------------------------------------- stereo pairs


def camera_info(name: str, camera: Pinhole, tx: float = 0.0) -> dict[str, Any]:
    """A ROS ``camera_info`` YAML document (camera_calibration_parsers layout) of a rectified, undistorted camera;
    ``tx`` is the projection matrix's P[0, 3] (−fx·baseline for the right camera of a pair)."""
    k = [camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0]
    p = [camera.fx, 0.0, camera.cx, tx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return {"image_width": camera.width, "image_height": camera.height, "camera_name": name,
            "camera_matrix": {"rows": 3, "cols": 3, "data": k},
            "distortion_model": "plumb_bob",
            "distortion_coefficients": {"rows": 1, "cols": 5, "data": [0.0] * 5},
            "rectification_matrix": {"rows": 3, "cols": 3, "data": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0]},
            "projection_matrix": {"rows": 3, "cols": 4, "data": p}}


@dataclass(frozen=True)
class StereoPair:
    """Left and right renders of one scene from a pair on the main axis, and their camera_info documents."""

    left: Render
    right: Render
    left_camera: Pinhole
    right_camera: Pinhole
    left_info: dict[str, Any]
    right_info: dict[str, Any]


def render_pair(scene: Scene, width: int = 541, height: int = 413, hfov_deg: float = 70.0,
                baseline_m: float = 0.5, pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
                lean_left_rad: float = 0.0, pitch_rad: float = 0.0, radius_m: float = 0.30,
                supersample: int = 2) -> StereoPair:
    """Render the pair on a sphere of radius ``radius_m`` at ``pose`` (x, y, yaw): left camera ``baseline_m``/2 to
    the left of the centre, right camera as far to the right, both looking forward along the heading."""
    x, y, yaw = pose
    cams = [camera_on_sphere(width, height, hfov_deg, x, y, yaw, radius_m, side * baseline_m / 2,
                             lean_left_rad, pitch_rad) for side in (1, -1)]
    left, right = (render(c, scene, supersample) for c in cams)
    return StereoPair(left, right, cams[0], cams[1], camera_info("left", cams[0]),
                      camera_info("right", cams[1], -cams[1].fx * baseline_m))


def write_pair(pair: StereoPair, folder: str | Path, stem: str = "") -> dict[str, Path]:
    """Write ``left.png``, ``right.png``, ``left.yaml``, ``right.yaml`` (prefixed by ``stem``) into ``folder``."""
    import yaml
    from PIL import Image

    folder = Path(folder)
    out = {}
    for side, rend, info in (("left", pair.left, pair.left_info), ("right", pair.right, pair.right_info)):
        out[f"{side}_png"] = folder / f"{stem}{side}.png"
        out[f"{side}_yaml"] = folder / f"{stem}{side}.yaml"
        Image.fromarray(rend.image).save(out[f"{side}_png"])
        out[f"{side}_yaml"].write_text(yaml.safe_dump(info, sort_keys=False))
    return out


def write_demo(folder: str | Path = ".") -> None:
    """The docs' example files: the obstacle course as a 541 × 413 pair (``left.png``, ``right.png``,
    ``left.yaml``, ``right.yaml``), a frame from a camera rolled 10° and pitched 5° (``rolled.png``, with
    ``camera.yaml``) and a two-frame folder with its IMU CSV (``frames/``, ``imu.csv``)."""
    import yaml
    from PIL import Image

    folder = Path(folder)
    write_pair(render_pair(obstacle_course()), folder)
    cam = camera_with_attitude(541, 413, 70.0, (0.0, 0.0, 0.3), math.radians(10), math.radians(5))
    Image.fromarray(render(cam, horizon_scene()).image).save(folder / "rolled.png")
    (folder / "camera.yaml").write_text(yaml.safe_dump(camera_info("camera", cam), sort_keys=False))
    frames = folder / "frames"
    frames.mkdir(exist_ok=True)
    rows = ["time,roll,pitch"]
    for i, (roll, pitch) in enumerate(((4.0, -2.0), (-6.0, 3.0))):
        cam = camera_with_attitude(541, 413, 70.0, (0.0, 0.0, 0.3), math.radians(roll), math.radians(pitch))
        Image.fromarray(render(cam, horizon_scene(), supersample=1).image).save(frames / f"frame{i:03d}.png")
        rows.append(f"{i * 0.1:.1f},{math.radians(roll):.6f},{math.radians(pitch):.6f}")
    (folder / "imu.csv").write_text("\n".join(rows) + "\n")
