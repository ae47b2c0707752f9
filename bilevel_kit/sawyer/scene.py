"""An animated 3-D view of an execution: one standalone HTML page (docs/execution.md).

The page is meshcat's static viewer (its ``main.min.js``, three.js inside, MIT licensed)
inlined with the scene's commands, so it opens from a file and fetches nothing. The scene, in
the robot base frame: the pedestal, the arm's links as cylinders between consecutive joint
origins (from the kinematic model), joint housings, the electric gripper, the part bins, the
table, one tray per kit, and each part, which appears at its bin when the gripper closes,
rides with the gripper and stays on its slot. A kit's tray appears when the robot starts the
kit, slides to the human's table during the delivery, and disappears when the human takes
its parts (``o_H`` after starting the kit). An overlay shows the kit number, the plan time,
what the robot and the human do, and one button per kit that jumps to its start.

Animation time 0 is plan time ``t0`` (0, or the kit's start with one kit); keyframes are in
frames of :data:`FPS` per second of plan time, played :data:`SPEED` times faster with the
whole plan. ``window.bilevelKit`` exposes the data (kits with their frame ranges, steps) and
``seek(plan_time)`` for tests and talks.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic, style
from .model import HAND_RPY, HAND_XYZ, JOINT_TABLE, Arm
from .trajectory import Execution

#: Animation frames per second of plan time.
FPS = 30
#: Keyframes per second of arm motion.
KEY_RATE = 10.0
#: Playback speed: the whole plan plays this many times faster; one kit in real time.
SPEED = 4.0
#: How far the tray slides towards the human when delivered [m, base x].
PUSH = 0.55
ARM_COLOR = 0xB0242C
JOINT_COLOR = 0x3A3A3A
GRIPPER_COLOR = 0x555555
TRAY_COLOR = 0xD9C9A3
TABLE_COLOR = 0x8D99AE
BIN_COLOR = 0x4F6D7A
#: Link radii [m], right_l0 .. right_l6.
LINK_RADII = (0.06, 0.055, 0.05, 0.045, 0.04, 0.04, 0.035)
#: The floor under the pedestal: a slab, top at :data:`FLOOR_Z` [m], and its colour.
FLOOR_SIZE = (3.0, 3.0, 0.01)
FLOOR_COLOR = 0xC8CCD2
#: Height of a bin's rim above its grasp point [m].
BIN_RIM = 0.01
#: Pedestal height below the base [m] (the floor).
FLOOR_Z = -0.91
#: Where the view looks at (base frame) and the camera's offset from there [m].
CENTRE = (0.4, 0.1, -0.15)
CAMERA = (1.1, -0.85, 0.6)
_UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def _meshcat() -> Any:
    """Import meshcat, whose package imports its server's deprecated zmq modules."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import meshcat
    return meshcat


def _tf(xyz: Any = (0.0, 0.0, 0.0), rot: np.ndarray | None = None) -> np.ndarray:
    m = np.eye(4)
    if rot is not None:
        m[:3, :3] = rot
    m[:3, 3] = np.asarray(xyz, dtype=float)
    return m


def _rz(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (f(a) for a in (r, p, y) for f in (math.cos, math.sin))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rzz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rzz @ ry @ rx


def _along(v: Any) -> np.ndarray:
    """Transform putting a y-axis cylinder (three.js) centred on the segment 0 -> v."""
    v = np.asarray(v, dtype=float)
    n = float(np.linalg.norm(v))
    y = v / n
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    return _tf(v / 2.0, np.column_stack([x, y, z]))


def _quat(rot: np.ndarray) -> list[float]:
    """[x, y, z, w] of a rotation matrix (three.js order)."""
    from scipy.spatial.transform import Rotation

    return [round(float(v), 6) for v in Rotation.from_matrix(rot).as_quat()]


def _hex(color: str) -> int:
    return int(color.lstrip("#"), 16)


class _Scene:
    """Collects meshcat commands and keyframes (plan times in, frames out)."""

    def __init__(self, t0: float, t1: float) -> None:
        from meshcat.animation import Animation

        self.t0, self.t1 = t0, t1
        self.commands: list[dict[str, Any]] = []
        self.animation = Animation(default_framerate=FPS)

    def path(self, name: str) -> Any:
        from meshcat.path import Path as MPath

        return MPath(tuple(name.strip("/").split("/")))

    def solid(
        self,
        name: str,
        geometry: Any,
        color: int,
        transform: np.ndarray | None = None,
        opacity: float = 1.0,
    ) -> None:
        from meshcat.commands import SetObject
        from meshcat.geometry import MeshLambertMaterial

        material = MeshLambertMaterial(color=color, opacity=opacity)
        self.commands.append(SetObject(geometry, material, self.path(name)).lower())
        if transform is not None:
            self.place(name, transform)

    def place(self, name: str, transform: np.ndarray) -> None:
        from meshcat.commands import SetTransform

        self.commands.append(SetTransform(transform, self.path(name)).lower())

    def prop(self, name: str, key: str, value: Any) -> None:
        from meshcat.commands import SetProperty

        self.commands.append(SetProperty(key, value, self.path(name)).lower())

    def frame(self, t: float) -> float:
        return round((min(max(t, self.t0), self.t1) - self.t0) * FPS, 4)

    def _clip(self, name: str) -> Any:
        from meshcat.animation import AnimationClip

        key = self.path(name)
        if key not in self.animation.clips:
            self.animation.clips[key] = AnimationClip(fps=FPS)
        return self.animation.clips[key]

    def pose(self, name: str, t: float, transform: np.ndarray) -> None:
        clip = self._clip(name)
        frame = self.frame(t)
        clip.set_property(frame, "position", "vector3", [round(v, 5) for v in transform[:3, 3]])
        clip.set_property(frame, "quaternion", "quaternion", _quat(transform[:3, :3]))

    def visible(self, name: str, t: float, shown: bool) -> None:
        self._clip(name).set_property(self.frame(t), "visible", "boolean", shown)

    def finish(self) -> None:
        """Every track holds its last value until the end, so all clips last as long."""
        end = self.frame(self.t1)
        for clip in self.animation.clips.values():
            for track in clip.tracks.values():
                if track.frames[-1] < end:
                    track.set_property(end, track.values[-1])


def _work_cell(scene: _Scene, ex: Execution) -> None:
    """Pedestal, table, human's table and bins (static)."""
    from meshcat.geometry import Box, Cylinder

    s = ex.work_cell
    # the nodes keep their "bk/station/" paths (the page's scene tree, which the tests and a
    # viewer's controls address): the rename to work cell changes no page
    floor = _tf((0.4, 0.0, FLOOR_Z - FLOOR_SIZE[2] / 2))
    scene.solid("bk/station/floor", Box(list(FLOOR_SIZE)), FLOOR_COLOR, floor)
    pedestal = _tf((-0.02, 0.0, 0.0)) @ _along([0.0, 0.0, FLOOR_Z])
    scene.solid("bk/station/pedestal", Cylinder(-FLOOR_Z, 0.16), 0x2B2B2B, pedestal)
    corners = np.array([s.tray_to_base(x, y) for x in (0, ex.tray[0]) for y in (0, ex.tray[1])])
    bins = {tuple(s.bin_xyz(t)) for layout in ex.layouts.values() for t in {p.type for p in layout}}
    z = s.tray_z / 1000.0
    # The robot's table holds the tray and the bins (whose grasp points lie above it).
    held = np.vstack([corners, np.array(sorted(bins)).reshape(-1, 3) / 1000.0])
    for name, dx, pts in (("table", 0.0, held), ("human_table", PUSH, corners)):
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        size = [hi[0] - lo[0] + 0.3, hi[1] - lo[1] + 0.3, 0.04]
        centre = [(lo[0] + hi[0]) / 2 + dx, (lo[1] + hi[1]) / 2, z - 0.02 - 0.012]
        scene.solid(f"bk/station/{name}", Box(size), TABLE_COLOR, _tf(centre), 0.9)
    for i, xyz in enumerate(sorted(bins)):
        p = np.array(xyz) / 1000.0
        height = max(p[2] - z + BIN_RIM, BIN_RIM)  # from the table top to above the grasp point
        scene.solid(
            f"bk/station/bin{i}",
            Box([0.16, 0.16, height]),
            BIN_COLOR,
            _tf((p[0], p[1], z + height / 2)),
            0.55,
        )


def _arm_geometry(scene: _Scene) -> None:
    """Each link ``right_l{i}`` as a node holding a joint housing and a cylinder to the next
    joint origin (or to the flange), plus the gripper on ``right_l6``."""
    from meshcat.geometry import Box, Cylinder

    scene.solid("bk/robot/base", Cylinder(0.08, 0.09), JOINT_COLOR, _along([0, 0, 0.08]))
    for i, radius in enumerate(LINK_RADII):
        node = f"bk/robot/l{i}"
        housing = _tf((0, 0, 0), _rpy(math.pi / 2, 0, 0))
        scene.solid(f"{node}/joint", Cylinder(2.2 * radius, radius * 1.15), JOINT_COLOR, housing)
        nxt = np.array(JOINT_TABLE[i + 1][1]) if i < 6 else np.array(HAND_XYZ)
        if np.linalg.norm(nxt) > 1e-6:
            scene.solid(f"{node}/link", Cylinder(float(np.linalg.norm(nxt)), radius), ARM_COLOR)
            scene.place(f"{node}/link", _along(nxt))
    hand = "bk/robot/l6/hand"
    scene.place(hand, _tf(HAND_XYZ, _rpy(*HAND_RPY)))
    scene.solid(f"{hand}/body", Box([0.09, 0.05, 0.05]), GRIPPER_COLOR, _tf((0, 0, 0.035)))
    for side in ("l", "r"):
        scene.solid(f"{hand}/finger_{side}", Box([0.012, 0.012, 0.075]), GRIPPER_COLOR)


def _finger_offset(side: str, closed: bool) -> np.ndarray:
    gap = 0.008 if closed else 0.030
    return _tf((0.0, gap if side == "l" else -gap, 0.06 + 0.0375))


def _link_poses(arm: Arm, q: np.ndarray) -> list[np.ndarray]:
    """World transforms of ``right_l0..6`` and of the tool at ``q``."""
    import pinocchio as pin

    pin.framesForwardKinematics(arm.model, arm.data, q)
    ids = [arm.model.getFrameId(f"right_l{i}") for i in range(7)] + [arm.tool_id]
    return [arm.data.oMf[f].homogeneous.copy() for f in ids]


def _arm_samples(ex: Execution, t0: float, t1: float) -> list[tuple[float, np.ndarray]]:
    """(plan time, q) keys of the arm: dense during each kit's motion, held in between."""
    out: list[tuple[float, np.ndarray]] = []
    for kt in ex.kits:
        n = max(2, math.ceil(kt.duration * KEY_RATE) + 1)
        marks = [s.start for s in kt.segments] + [kt.duration]
        ts = np.unique(np.concatenate([np.linspace(0.0, kt.duration, n), marks]))
        if not out:
            out.append((t0, kt.positions[0]))
        out += [(kt.start + float(t), q) for t, q in zip(ts, kt.positions_at(ts), strict=True)]
    if out:
        out.append((t1, out[-1][1]))
    return out


def _animate_arm(scene: _Scene, ex: Execution, arm: Arm) -> dict[float, np.ndarray]:
    """Arm keyframes; returns the tool pose at every key time."""
    tool: dict[float, np.ndarray] = {}
    for t, q in _arm_samples(ex, scene.t0, scene.t1):
        poses = _link_poses(arm, q)
        for i in range(7):
            scene.pose(f"bk/robot/l{i}", t, poses[i])
        tool[t] = poses[7]
    for t, _kit, _part, closed in ex.gripper_commands():
        for side in ("l", "r"):
            scene.pose(f"bk/robot/l6/hand/finger_{side}", t, _finger_offset(side, closed))
    if not ex.kits:
        for side in ("l", "r"):
            scene.place(f"bk/robot/l6/hand/finger_{side}", _finger_offset(side, False))
    return tool


def _animate_kits(scene: _Scene, ex: Execution, tool: dict[float, np.ndarray]) -> None:
    """Trays (appear, slide to the human, vanish) and parts (appear, ride, stay)."""
    from meshcat.geometry import Box

    s = ex.work_cell
    home = _tf(np.array([s.tray_x, s.tray_y, s.tray_z]) / 1000.0, _rz(s.tray_yaw))
    away = _tf([PUSH, 0, 0]) @ home
    colors = {t: _hex(style.PALETTE[i % len(style.PALETTE)]) for i, t in enumerate(ex.part_types)}
    w, h = ex.tray[0] / 1000.0, ex.tray[1] / 1000.0
    key_times = np.array(sorted(tool))
    trajectories = {kt.kit: kt for kt in ex.kits}
    for k, layout in ex.layouts.items():
        times = ex.timeline.kits[k - 1]
        node = f"bk/kits/k{k}"
        scene.solid(f"{node}/tray", Box([w, h, 0.012]), TRAY_COLOR, _tf((w / 2, h / 2, -0.006)))
        scene.place(node, home)
        gone = times.human_start + ex.kit_overhead_human[k - 1]
        if times.robot_start > scene.t0:
            scene.visible(node, scene.t0, False)
        scene.visible(node, times.robot_start, True)
        if gone < scene.t1:
            scene.visible(node, gone, False)
        scene.pose(node, times.robot_end, home)
        scene.pose(node, times.arrive, away)
        kt = trajectories.get(k)
        for j, p in enumerate(layout):
            thick = min(max(min(p.w, p.h), 3.0), 20.0) / 1000.0
            slot = _tf((p.x / 1000.0, p.y / 1000.0, thick / 2), _rz(p.theta))
            part = f"{node}/p{j}"
            scene.solid(f"{part}/box", Box([p.w / 1000.0, p.h / 1000.0, thick]), colors[p.type])
            scene.place(part, slot)
            if kt is None:
                continue
            motion = kt.parts[j]
            grasp, release = kt.start + motion.grasp_at, kt.start + motion.release_at
            carry = np.linalg.inv(tool[_nearest(key_times, release)]) @ home @ slot
            scene.visible(part, scene.t0, False)
            scene.visible(part, grasp, True)
            for t in key_times[(key_times >= grasp - 1e-9) & (key_times < release - 1e-9)]:
                scene.pose(part, float(t), np.linalg.inv(home) @ tool[float(t)] @ carry)
            scene.pose(part, release, slot)


def _nearest(times: np.ndarray, t: float) -> float:
    return float(times[int(np.argmin(np.abs(times - t)))])


def _overlay_data(ex: Execution, t0: float, t1: float, speed: float) -> dict[str, Any]:
    """What the page's overlay shows, in plan seconds."""
    kits = []
    for k in ex.layouts:
        times = ex.timeline.kits[k - 1]
        kits.append(
            {
                "kit": k,
                "start": times.robot_start,
                "end": times.arrive,
                "push": times.robot_end,
                "first": round((times.robot_start - t0) * FPS, 4),
                "last": round((min(times.arrive, t1) - t0) * FPS, 4),
                "parts": len(ex.layouts[k]),
            }
        )
    steps = [
        [kt.start + s.start, kt.start + s.end, kt.kit, s.part, s.name]
        for kt in ex.kits
        for s in kt.segments
    ]
    arm = {kt.kit: [kt.start, kt.end] for kt in ex.kits}
    human = []
    for k in range(1, len(ex.timeline.kits) + 1):
        times = ex.timeline.kits[k - 1]
        human.append(
            [times.human_start, times.human_start + ex.kit_overhead_human[k - 1], f"takes kit {k}"]
        )
    human += [
        [ex.timeline.task_start[t], ex.timeline.task_end[t], f"task {t}"]
        for t in ex.timeline.task_start
    ]
    return {
        "instance": ex.instance,
        "fps": FPS,
        "t0": t0,
        "t1": t1,
        "speed": speed,
        "n_plan_kits": ex.n_plan_kits,
        "kits": kits,
        "arm": arm,
        "steps": steps,
        "human": sorted(human),
    }


def scene_commands(execution: Execution) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """The meshcat commands of the scene and the overlay's data."""
    _meshcat()
    from meshcat.commands import SetAnimation

    ex = execution
    first = min(ex.layouts)
    one = len(ex.layouts) == 1
    t0 = ex.timeline.kits[first - 1].robot_start if one else 0.0
    t1 = ex.timeline.kits[first - 1].arrive + 1.0 if one else ex.timeline.makespan
    scene = _Scene(t0, t1)
    arm = Arm(ex.work_cell.tool_offset_m)
    _work_cell(scene, ex)
    _arm_geometry(scene)
    tool = _animate_arm(scene, ex, arm)
    _animate_kits(scene, ex, tool)
    scene.finish()
    centre = np.array(CENTRE)
    scene.place("bk", _tf(-centre))
    scene.prop("Grid", "visible", False)  # meshcat's 20 m grid: replaced by the floor
    scene.prop("Axes", "visible", False)
    # The camera sits in three.js's y-up frame: our (x, y, z) is its (x, z, -y).
    eye = CAMERA
    scene.prop("Cameras/default/rotated/<object>", "position", [eye[0], eye[2], -eye[1]])
    speed = 1.0 if one else SPEED
    scene.commands.append(SetAnimation(scene.animation, play=True, repetitions=1000).lower())
    return scene.commands, _overlay_data(ex, t0, t1, speed)


def _script_json(value: Any) -> str:
    """JSON safe inside a <script> element, with meshcat's random uuids made sequential."""
    text = json.dumps(value, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    seen: dict[str, str] = {}

    def number(m: re.Match[str]) -> str:
        return seen.setdefault(m.group(0), f"00000000-0000-4000-8000-{len(seen):012x}")

    return _UUID.sub(number, text)


def viewer_js() -> str:
    """meshcat's bundled viewer (three.js inside), to inline."""
    js = Path(_meshcat().viewer_assets_path()) / "dist" / "main.min.js"
    return js.read_text(encoding="utf-8")


def html_page(execution: Execution) -> str:
    """The standalone page (see the module docstring)."""
    commands, data = scene_commands(execution)
    page = Path(__file__).with_name("scene.html").read_text(encoding="utf-8")
    parts = {
        "TITLE": _html_escape(f"{execution.instance}: kitting on the Sawyer"),
        "VIEWER_JS": viewer_js().replace("</script", "<\\/script"),
        "DATA": _script_json(data),
        "COMMANDS": _script_json(commands),
    }
    return re.sub(r"\{\{([A-Z_]+)\}\}", lambda m: parts[m.group(1)], page)


def _html_escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def write_html(execution: Execution, path: str | Path) -> int:
    """Write the page atomically; returns its size in bytes."""
    text = html_page(execution)
    atomic.write_text(path, text)
    return len(text.encode("utf-8"))
