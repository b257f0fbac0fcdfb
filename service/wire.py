"""Wire models: the JSON requests the HTTP API and the Zenoh node accept, as strict Pydantic models.

They are kept apart from the planner's own types (``planner/`` never imports pydantic) and named apart
from them (:class:`ReconfigureIn` here, ``planner.spherobot.request.ReconfigureRequest`` there); the
planning service turns each into the planner's typed objects once. Every request model forbids unknown
fields, rejects wrong types (no "1" for 1, no true for 1) and NaN/±inf, and bounds sizes, so a bad
request is rejected before it reaches a worker process. Poses are in the ``map`` frame (metres, radians,
yaw counter-clockwise). Response bodies are the plan result JSON of docs/contracts.md; their models here
only document them in the OpenAPI schema (extra keys allowed).

Map and robot names are plain names (letters, digits, ``_``, ``-``, ``.``; no ``/``, no leading dot):
they are looked up in the maps folder listing and the built-in profiles, never joined onto a path.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    RootModel,
    Tag,
    ValidationInfo,
    field_validator,
    model_validator,
)

from planner.angles import check_angle
from planner.errors import InvalidInput
from service.settings import MAX_INLINE_CELLS, MAX_TIME_LIMIT_S

#: longest plan ``/v1/simulate`` accepts (states; 20 000 × 4 cm = 800 m)
MAX_PLAN_STATES = 20_000
#: longest path (m, along the states) ``/v1/simulate`` and ``/v1/vpip/schedule`` roll
MAX_PLAN_LENGTH_M = 200.0
#: longest simulated time ``/v1/simulate`` accepts (s)
MAX_SIM_TIME_S = 3600.0

#: largest |coordinate| accepted (m) and largest |angle| (rad or degrees)
MAX_COORDINATE_M = 1e6
MAX_ANGLE = 1e4

NAME_PATTERN = r"^[A-Za-z0-9_-][A-Za-z0-9_.-]{0,63}$"

Name = Annotated[str, Field(pattern=NAME_PATTERN, description="a plain name: no '/', no leading '.'")]
#: a position (m): bounded so that no computation meets absurd magnitudes
Metres = Annotated[float, Field(ge=-MAX_COORDINATE_M, le=MAX_COORDINATE_M, description="m")]
#: an angle (rad, or degrees where the request says so)
Angle = Annotated[float, Field(ge=-MAX_ANGLE, le=MAX_ANGLE)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


#: how a wire request gives degrees, where a model has a ``degrees`` flag
DEGREES_HINT = '"degrees": true'


def _wire_angle(value: float | None, degrees: bool, hint: str) -> float | None:
    """The shared angle rule (:func:`planner.angles.check_angle`) as a pydantic validator: a value in radians
    (or degrees when ``degrees``) outside [−2π, 2π] is refused at its own field."""
    if value is None:
        return None
    try:
        check_angle("angle", math.radians(value) if degrees else value, hint)
    except InvalidInput as exc:
        raise ValueError(exc.msg) from None
    return value


def _degrees_of(info: ValidationInfo) -> bool:
    """The request's ``degrees`` flag (declared before its angles, so it is validated first)."""
    return bool(info.data.get("degrees", False))


class PoseIn(_Strict):
    """A planar pose in the ``map`` frame: ``yaw`` in radians in [−2π, 2π], or ``yaw_deg`` in degrees (one of
    the two)."""

    x: Metres
    y: Metres
    yaw: Angle | None = Field(default=None, description="rad, counter-clockwise from +x, in [−2π, 2π]")
    yaw_deg: Angle | None = Field(default=None, description="the yaw in degrees instead (in [−360, 360])")

    @field_validator("yaw")
    @classmethod
    def _yaw_rad(cls, value: float | None) -> float | None:
        return _wire_angle(value, False, "yaw_deg")

    @field_validator("yaw_deg")
    @classmethod
    def _yaw_deg(cls, value: float | None) -> float | None:
        return _wire_angle(value, True, "yaw_deg")

    @model_validator(mode="after")
    def _one_yaw(self) -> PoseIn:
        if (self.yaw is None) == (self.yaw_deg is None):
            raise ValueError("give the yaw as exactly one of yaw (rad) and yaw_deg (degrees)")
        return self

    def as_pose(self) -> tuple[float, float, float]:
        yaw = self.yaw if self.yaw is not None else math.radians(self.yaw_deg or 0.0)
        return self.x, self.y, yaw


class InlineGrid(_Strict):
    """An occupancy grid sent inline: ``data[iy][ix]`` in 0..100 (percent) or −1 (unknown), row 0 at
    the BOTTOM (y = origin y), as ``nav_msgs/OccupancyGrid``; at most ``MAX_INLINE_CELLS`` cells."""

    data: list[list[Annotated[int, Field(ge=-1, le=100)]]] = Field(min_length=1)
    resolution_m: float = Field(ge=0.001, le=100)
    origin: list[Metres] = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3,
                                 description="[x m, y m, yaw rad] of the lower-left corner of cell (0, 0)")
    name: Name = "inline"

    @model_validator(mode="after")
    def _rectangular(self) -> InlineGrid:
        width = len(self.data[0])
        if width == 0 or any(len(row) != width for row in self.data):
            raise ValueError("data must be a non-empty rectangular list of rows")
        if width * len(self.data) > MAX_INLINE_CELLS:
            raise ValueError(f"data has {width * len(self.data)} cells; at most {MAX_INLINE_CELLS} are accepted")
        return self



# ------------------------------------------------------------------------ ROS 2 messages in their JSON form
# geometry_msgs/Pose, geometry_msgs/PoseStamped and nav_msgs/OccupancyGrid as rosbridge, Foxglove and
# ``ros2 topic echo --json`` spell them; accepted wherever a pose or a map is (docs/ros2.md).

#: the frames a stamped pose or a map may be in ("" = unset, taken as map)
MAP_FRAMES = ("", "map", "/map")


class RosTime(_Strict):
    """``builtin_interfaces/Time``."""

    sec: int = Field(default=0, ge=-(2**31), le=2**31 - 1)
    nanosec: int = Field(default=0, ge=0, le=999_999_999)


class RosHeader(_Strict):
    """``std_msgs/Header``; ``frame_id`` must be the map frame (``map``, or empty)."""

    stamp: RosTime = Field(default_factory=RosTime)
    frame_id: str = Field(default="", max_length=256)

    @field_validator("frame_id")
    @classmethod
    def _map_frame(cls, frame: str) -> str:
        if frame not in MAP_FRAMES:
            raise ValueError(f"sphereplan plans in the 'map' frame; got frame_id {frame!r} (transform it first)")
        return frame


class RosPoint(_Strict):
    """``geometry_msgs/Point`` (z is ignored: the sphere rolls on the map plane)."""

    x: Metres
    y: Metres
    z: Metres = 0.0


class RosQuaternion(_Strict):
    """``geometry_msgs/Quaternion``; need not be unit length, must not be zero. Only its yaw is used."""

    x: float = Field(default=0.0, ge=-1e3, le=1e3)
    y: float = Field(default=0.0, ge=-1e3, le=1e3)
    z: float = Field(default=0.0, ge=-1e3, le=1e3)
    w: float = Field(default=1.0, ge=-1e3, le=1e3)

    @model_validator(mode="after")
    def _not_zero(self) -> RosQuaternion:
        if math.hypot(self.x, self.y, self.z, self.w) < 1e-9:
            raise ValueError("the orientation quaternion is zero")
        return self

    def yaw(self) -> float:
        return math.atan2(2 * (self.w * self.z + self.x * self.y), 1 - 2 * (self.y * self.y + self.z * self.z))


class RosPose(_Strict):
    """``geometry_msgs/Pose`` in the ``map`` frame."""

    position: RosPoint
    orientation: RosQuaternion = Field(default_factory=RosQuaternion)

    def as_pose(self) -> tuple[float, float, float]:
        return self.position.x, self.position.y, self.orientation.yaw()


class RosPoseStamped(_Strict):
    """``geometry_msgs/PoseStamped``; ``header.frame_id`` must be ``map`` (or empty)."""

    header: RosHeader = Field(default_factory=RosHeader)
    pose: RosPose

    def as_pose(self) -> tuple[float, float, float]:
        return self.pose.as_pose()


def _pose_kind(value: Any) -> str:
    if isinstance(value, dict | BaseModel):
        keys = value.keys() if isinstance(value, dict) else type(value).model_fields.keys()
        if "pose" in keys:
            return "PoseStamped"
        if "position" in keys:
            return "Pose"
    return "PoseIn"


#: a pose as ``{x, y, yaw}``, a ``geometry_msgs/Pose`` or a ``geometry_msgs/PoseStamped`` (told apart by
#: their keys, so errors name the fields of the form that was sent)
PoseSpec = Annotated[
    Annotated[PoseIn, Tag("PoseIn")] | Annotated[RosPose, Tag("Pose")] | Annotated[RosPoseStamped, Tag("PoseStamped")],
    Discriminator(_pose_kind),
]


class PoseMessage(RootModel[PoseSpec]):
    """A pose in any of its accepted forms (the Zenoh ``pose`` topic)."""

    def as_pose_in(self) -> PoseIn:
        x, y, yaw = self.root.as_pose()
        return PoseIn(x=x, y=y, yaw=yaw)


class RosMapMetaData(_Strict):
    """``nav_msgs/MapMetaData``."""

    map_load_time: RosTime = Field(default_factory=RosTime)
    resolution: float = Field(ge=0.001, le=100, description="m per cell")
    width: int = Field(ge=1, le=MAX_INLINE_CELLS)
    height: int = Field(ge=1, le=MAX_INLINE_CELLS)
    origin: RosPose = Field(description="pose of the lower-left corner of cell (0, 0)")


#: longest ``data_gzip_b64`` accepted (characters); the body limit caps it too
MAX_GZIP_B64_CHARS = 8_000_000


def gunzip_cells(text: str, cells: int) -> bytes:
    """The int8 cells of a ``data_gzip_b64`` (base64 of gzip, or of zlib, of the row-major int8 data), read with
    memory bounded by ``cells``: decompression stops one byte past it, so a small bomb cannot fill memory."""
    import base64
    import binascii
    import zlib

    try:
        packed = base64.b64decode(text, validate=True)
    except (binascii.Error, ValueError):
        raise ValueError("data_gzip_b64 is not valid base64") from None
    inflater = zlib.decompressobj(wbits=47)  # 32 + 15: gzip or zlib header, detected
    try:
        raw = inflater.decompress(packed, cells + 1)
    except zlib.error as exc:
        raise ValueError(f"data_gzip_b64 is not gzip/zlib data: {exc}") from None
    if len(raw) != cells or inflater.unconsumed_tail:
        more = "more than" if len(raw) > cells or inflater.unconsumed_tail else str(len(raw)) + " bytes, not"
        raise ValueError(f"data_gzip_b64 holds {more} info.width × info.height = {cells} cells")
    values = np.frombuffer(raw, dtype=np.int8)
    bad = (values < -1) | (values > 100)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"data_gzip_b64 cell {i} is {int(values[i])}; cells are 0..100 or -1 (unknown)")
    return raw


class RosOccupancyGrid(_Strict):
    """``nav_msgs/OccupancyGrid`` in its ROS JSON form: ``data`` row-major, ``width`` cells per row, row 0 at
    the origin, values 0..100 or −1 (unknown); at most ``MAX_INLINE_CELLS`` cells. Big maps may send
    ``data_gzip_b64`` instead of ``data``: the same cells as int8 bytes, gzip-compressed, then base64 — a
    2000 × 2000 map (100 m × 100 m at 5 cm) is typically tens of kB."""

    header: RosHeader = Field(default_factory=RosHeader)
    info: RosMapMetaData
    data: list[Annotated[int, Field(ge=-1, le=100)]] | None = Field(default=None, min_length=1,
                                                                     max_length=MAX_INLINE_CELLS)
    data_gzip_b64: str | None = Field(default=None, min_length=1, max_length=MAX_GZIP_B64_CHARS,
                                      description="base64 of gzip of the int8 cells (instead of data)")

    @model_validator(mode="after")
    def _size(self) -> RosOccupancyGrid:
        cells = self.info.width * self.info.height
        if cells > MAX_INLINE_CELLS:
            raise ValueError(f"info.width × info.height = {cells} cells; at most {MAX_INLINE_CELLS} are accepted")
        if (self.data is None) == (self.data_gzip_b64 is None):
            raise ValueError("give the cells as exactly one of data (a list) and data_gzip_b64")
        if self.data is not None and len(self.data) != cells:
            raise ValueError(f"data has {len(self.data)} values; info.width × info.height = {cells}")
        if self.data_gzip_b64 is not None:
            gunzip_cells(self.data_gzip_b64, cells)
        return self

    def cells(self) -> np.ndarray:
        """The cells as an int8 array (height, width), row 0 at the origin."""
        w, h = self.info.width, self.info.height
        if self.data_gzip_b64 is not None:
            flat = np.frombuffer(gunzip_cells(self.data_gzip_b64, w * h), dtype=np.int8)
        else:
            flat = np.asarray(self.data, dtype=np.int8)
        return flat.reshape(h, w)

    def as_inline(self) -> InlineGrid:
        """The inline grid this message describes (its cells already checked: built without re-validation)."""
        x, y, yaw = self.info.origin.as_pose()
        return InlineGrid.model_construct(data=self.cells().tolist(), resolution_m=self.info.resolution,
                                          origin=[x, y, yaw], name="occupancy_grid")


def _map_kind(value: Any) -> str:
    if isinstance(value, str):
        return "str"
    if isinstance(value, RosOccupancyGrid) or (isinstance(value, dict) and "info" in value):
        return "OccupancyGrid"
    return "InlineGrid"


#: a map: a name in the maps folder, an inline grid, or a ``nav_msgs/OccupancyGrid`` (told apart by form)
MapSpec = Annotated[
    Annotated[Name, Tag("str")] | Annotated[InlineGrid, Tag("InlineGrid")]
    | Annotated[RosOccupancyGrid, Tag("OccupancyGrid")],
    Discriminator(_map_kind),
]


OptionValue = bool | int | float


class PlanRequest(_Strict):
    """``POST /v1/plan`` and the ``sphereplan/plan`` query: plan from ``start`` to ``goal``."""

    map: MapSpec = Field(description="name of a map in the maps folder (GET /v1/maps), an inline grid, or a "
                                     "nav_msgs/OccupancyGrid")
    start: PoseSpec = Field(description="{x, y, yaw}, a geometry_msgs/Pose or a geometry_msgs/PoseStamped (map frame)")
    goal: PoseSpec = Field(description="{x, y, yaw}, a geometry_msgs/Pose or a geometry_msgs/PoseStamped (map frame)")
    robot: Name | None = Field(default=None, description="built-in profile name (GET /v1/robots); default zju-60")
    time_limit_s: float | None = Field(default=None, gt=0, le=MAX_TIME_LIMIT_S, description="s; default 5")
    options: dict[Annotated[str, Field(max_length=64)], OptionValue] | None = Field(
        default=None, max_length=64, description="planner options (PlannerOptions field names)"
    )


class GoalMessage(_Strict):
    """Payload of ``sphereplan/<robot_id>/goal``: plan from the robot's latest pose to ``goal``."""

    map: MapSpec
    goal: PoseSpec
    robot: Name | None = None
    time_limit_s: float | None = Field(default=None, gt=0, le=MAX_TIME_LIMIT_S)
    options: dict[Annotated[str, Field(max_length=64)], OptionValue] | None = Field(default=None, max_length=64)

    def plan_request(self, start: PoseIn | RosPose | RosPoseStamped) -> PlanRequest:
        return PlanRequest(map=self.map, start=start, goal=self.goal, robot=self.robot,
                           time_limit_s=self.time_limit_s, options=self.options)


class StateIn(_Strict):
    """One row of a plan's ``states`` (docs/contracts.md): SI units, radians."""

    x: Metres
    y: Metres
    yaw: Angle
    roll: Angle
    v: Metres
    t: Metres
    s: Metres
    curvature: Metres


class RobotRef(BaseModel):
    model_config = ConfigDict(extra="allow", strict=True)

    name: Name


class PlanIn(BaseModel):
    """A plan result as ``/v1/plan`` returns it; only ``states`` (and ``robot.name``) are read, other keys
    are accepted and ignored."""

    model_config = ConfigDict(extra="allow", strict=True, allow_inf_nan=False)

    states: list[StateIn] = Field(min_length=2, max_length=MAX_PLAN_STATES)
    robot: RobotRef | None = None
    map: str | None = Field(default=None, max_length=256, description="the map the plan was made on")

    @model_validator(mode="after")
    def _not_too_long(self) -> PlanIn:
        length = sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(self.states, self.states[1:], strict=False))
        if length > MAX_PLAN_LENGTH_M:
            raise ValueError(f"states span {length:.0f} m; at most {MAX_PLAN_LENGTH_M:g} m are simulated here")
        return self


class SimulateRequest(_Strict):
    """``POST /v1/simulate`` and the ``sphereplan/simulate`` query: roll ``path`` (a plan result) in
    closed loop on ``map``, as ``sphereplan simulate --map M --path PLAN.json`` does."""

    map: MapSpec
    path: PlanIn
    robot: Name | None = Field(default=None, description="default: the plan's robot")
    seed: int = Field(default=0, ge=0, le=2**32 - 1, description="seeds every disturbance")
    noise: Literal["none", "default"] = "default"
    tracker: Literal["mpc", "pursuit"] = "mpc"
    rate_hz: float = Field(default=50.0, ge=1, le=200, description="control rate")
    horizon: int = Field(default=15, ge=1, le=100, description="MPC horizon (steps)")
    time_limit_s: float | None = Field(default=None, gt=0, le=MAX_SIM_TIME_S,
                                       description="simulated seconds (default 2 × rolling time + 20 s)")
    allow_other_map: bool = Field(default=False, description="roll a plan made on another map (refused otherwise)")
    allow_other_robot: bool = Field(default=False,
                                    description="roll a plan made for another robot (refused otherwise)")


class TensegrityStaticRequest(_Strict):
    """``POST /v1/tensegrity/static``: the four hybrid static states of TeXploR for slider angles θ1, θ2
    (as ``sphereplan tensegrity static``)."""

    degrees: bool = False
    theta1: Angle = Field(description="slider 1 angle (rad, or degrees with degrees=true)")
    theta2: Angle = Field(description="slider 2 angle (rad, or degrees with degrees=true)")
    verify: bool = Field(default=True, description="cross-check with a potential-energy minimisation")
    robot: Name = "texplor"

    @field_validator("theta1", "theta2")
    @classmethod
    def _angles(cls, value: float, info: ValidationInfo) -> float | None:
        return _wire_angle(value, _degrees_of(info), DEGREES_HINT)


#: longest base64 text of one image ``/v1/perceive`` accepts (characters); the HTTP body limit caps it too
MAX_IMAGE_BASE64 = 8_000_000


class PerceiveRequest(_Strict):
    """``POST /v1/perceive``: one stereo pair → obstacle points in the map frame (as ``sphereplan perceive``;
    paper 001 §3.2). Images are base64 of image files (PNG, JPEG, ...); camera infos are the camera_info YAML
    documents (``image_width``, ``camera_matrix``, ``projection_matrix``, ...) as JSON objects. ``roll`` is the
    sphere's (> 0 leans left), ``pitch`` the main axis's (REP-103); radians unless ``degrees``.
    The pose's yaw is given as on every pose of the wire: ``yaw`` (rad) or ``yaw_deg``."""

    left_image: str = Field(min_length=1, max_length=MAX_IMAGE_BASE64, description="base64 of the left image file")
    right_image: str = Field(min_length=1, max_length=MAX_IMAGE_BASE64, description="base64 of the right image file")
    left_info: dict[str, Any] = Field(description="the left camera_info document")
    right_info: dict[str, Any] = Field(description="the right camera_info document (P[0,3] = −fx·baseline)")
    pose: PoseIn
    roll: Angle = 0.0
    pitch: Angle = 0.0
    degrees: bool = False
    robot: Name | None = Field(default=None, description="built-in profile; its radius is the axis height")
    min_height_m: float = Field(default=0.05, ge=0.0, le=10.0)
    max_height_m: float | None = Field(default=None, gt=0.0, le=100.0)
    max_range_m: float = Field(default=10.0, gt=0.0, le=1000.0)
    min_blob_px: int = Field(default=20, ge=1, le=1_000_000)


Pair = Annotated[list[Metres], Field(min_length=2, max_length=2)]
AnglePair = Annotated[list[Angle], Field(min_length=2, max_length=2)]


class ReconfigureIn(_Strict):
    """``POST /v1/reconfigure`` and the ``sphereplan/reconfigure`` query: roll a Spherobot (paper 004) to
    ``goal`` with its camera point P on top (as ``sphereplan reconfigure``). Angles in radians unless
    ``degrees``; ``map`` (a name or an inline grid) checks the swept sphere against obstacles."""

    method: Literal["arc", "triangle"] = "arc"
    start: Pair = Field(description="[x, y] m")
    goal: Pair = Field(description="[x, y] m")
    start_tilt: AnglePair = Field(default_factory=lambda: [0.0, 0.0], description="[θ, α] of P at the start")
    start_spin: Angle = 0.0
    goal_heading: Angle | None = Field(default=None, description="azimuth of body +x at the goal; none = partial")
    alpha_final: Angle | None = Field(default=None, description="arc method: direction of the last roll")
    radius_m: float | None = Field(default=None, gt=0, le=100)
    roll_rate_rad_s: float | None = Field(default=None, gt=0, le=1000)
    degrees: bool = False
    map: MapSpec | None = None
    allow_unknown: bool = False


class VpipRodsRequest(_Strict):
    """``POST /v1/vpip/rods``: eq. 18 rod lengths for one VPIP plane, roll and pitch phase (paper 000), as
    ``sphereplan vpip rods``."""

    degrees: bool = False
    phi_vpip: Angle = Field(description="plane roll (rad, or degrees with degrees=true), > 0 lowers the left")
    theta_vpip: Angle = Field(description="plane pitch, > 0 drives forward")
    roll: Angle = Field(default=0.0, description="robot roll, > 0 leans left")
    pitch_phase: Angle = Field(default=0.0, description="how far the sphere has rolled")
    robot: Name = "daedalus"

    @field_validator("phi_vpip", "theta_vpip", "roll", "pitch_phase")
    @classmethod
    def _angles(cls, value: float, info: ValidationInfo) -> float | None:
        return _wire_angle(value, _degrees_of(info), DEGREES_HINT)


class VpipScheduleRequest(_Strict):
    """``POST /v1/vpip/schedule``: 100 Hz VPIP angles and rod lengths along a plan (the time series
    ``sphereplan vpip schedule --out`` writes)."""

    path: PlanIn
    robot: Name | None = Field(default=None, description="default: the plan's robot, else daedalus")
    driver: Literal["vpip", "simple"] = "vpip"


# ------------------------------------------------------------------------------------ response documentation


class _Open(BaseModel):
    model_config = ConfigDict(extra="allow")


class ErrorBody(_Open):
    """Every error: a Nav2 ``ComputePathToPose`` code (200 = unknown/other for non-planning errors) and a
    sentence; ``field`` names the offending request field when there is one. A failed plan (422) carries
    the whole failed-result JSON (``status: failed``), which has these two keys too."""

    error_code: int
    error_msg: str
    field: str | None = None


class StateOut(_Open):
    x: float
    y: float
    yaw: float
    roll: float
    v: float
    t: float
    s: float
    curvature: float


class PlanResultOut(_Open):
    """The plan result JSON of docs/contracts.md (the CLI prints the same object)."""

    status: str
    error_code: int
    error_msg: str
    planning_time_s: float
    length_m: float
    expansions: int
    robot: dict[str, Any] | None
    states: list[StateOut]
    path: dict[str, Any]


class MapInfo(_Open):
    name: str
    file: str
    kind: str


class RobotInfo(_Open):
    name: str
    radius_m: float
    max_roll_rad: float


class Health(_Open):
    status: str


# ------------------------------------------------------------------------------------------ error messages

# pydantic puts union branch tags ("constrained-str", "InlineGrid", "float" ...) into error locations
_UNION_TAG = re.compile(r"^(bool|int|float|str|constrained-\w+|function-\w+\[.*\]|[A-Z]\w*|(list|tuple|dict)\[.*\])$")
_WRONG_TYPE = {"string_type", "dict_type", "model_type", "model_attributes_type", "bool_type", "int_type",
               "float_type", "list_type", "bool_parsing", "int_from_float"}


def field_name(loc: Sequence[int | str]) -> str:
    """Dotted field name of a pydantic error location (``start.x``, ``map.data[3][1]``), union tags dropped."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif not _UNION_TAG.match(part) and part != "body":
            out += f".{part}" if out else part
    return out or "body"


def invalid_input(errors: Sequence[Any]) -> InvalidInput:
    """The :class:`InvalidInput` a list of pydantic error dicts amounts to: the most specific error first.

    Errors saying "wrong type" for one branch of a union are only reported when nothing more specific
    was found (``map: "../x"`` reports the name pattern, not "should be an object").
    """
    specific = [e for e in errors if e.get("type") not in _WRONG_TYPE] or list(errors)
    first = max(specific, key=lambda e: len(e.get("loc", ())))
    if first.get("type") == "json_invalid":
        loc = first.get("loc", ())
        where = f" at character {loc[-1]}" if loc and isinstance(loc[-1], int) else ""
        return InvalidInput("body", f"malformed JSON{where}: {(first.get('ctx') or {}).get('error', first.get('msg'))}")
    field = field_name(first.get("loc", ()))
    msg = str(first.get("msg", "invalid value")).removeprefix("Value error, ")
    others = len({f for f in (field_name(e.get("loc", ())) for e in errors) if not field.startswith(f)})
    return InvalidInput(field, msg + (f" (and {others} more field(s))" if others else ""))
