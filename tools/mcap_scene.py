"""The 3-D scene of a Foxglove-family MCAP file in world coordinates, as a viewer draws it.

Knows nothing of gripopt's code: it reads `foxglove.FrameTransforms` on /tf and
`foxglove.SceneUpdate` on /scene and /scene/static (decoded by the caller with the reference
readers), keeps the latest transform of every frame the way a viewer does after a seek (the
latest /tf message at or before the playback time), composes the transforms itself up to the
fixed frame `world`, and checks the drawn geometry there:

* every /tf message carries `world -> hand`, the hand level (its z axis along world z), the
  same transform throughout each design's window (a file of several objects may hold a hand
  height per object: `world_hands` is the set);
* the ground is a cube in `world` whose top face is the ground plane;
* no point of a finger rod (line strip points, less half the line thickness) is below the
  ground plane at any instant a finger pose is drawn;
* at each design's window start the object (the cylinder `object`) stands upright (its axis
  along world z) with its base on the ground plane, i.e. at rest on the ground;
* a moving object frame (`hand -> object`) never takes the object's lowest rim point below the
  ground by more than the contact law's penetration (0.1 mm here; Hertz penetrations are µm).
"""
import math

GROUND_TOL = 1e-6  # m: fingers never touch the ground in the model
BASE_TOL = 1e-5  # m: the free object is pre-sunk by delta_g0 ~ 1e-6 m (MODEL.md §14.1)
PENETRATION_TOL = 1e-4  # m: a moving object may press into the ground by a Hertz penetration
UPRIGHT_TOL = 1e-9  # 1 - cos(tilt)


def quat_mat(q):
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mat_vec(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


class Rigid:
    """A rigid transform p -> R p + t."""

    def __init__(self, r=None, t=None):
        self.r = r or [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
        self.t = t or [0.0, 0.0, 0.0]

    @staticmethod
    def of_pose(position, orientation):
        return Rigid(quat_mat((orientation.x, orientation.y, orientation.z, orientation.w)), [position.x, position.y, position.z])

    def then(self, inner):
        """self ∘ inner (apply inner first)."""
        return Rigid(mat_mul(self.r, inner.r), [a + b for a, b in zip(mat_vec(self.r, inner.t), self.t)])

    def apply(self, p):
        return [a + b for a, b in zip(mat_vec(self.r, p), self.t)]


def transform_key(x):
    """A transform's value, for comparing frames between messages and files."""
    return (x.parent_frame_id, x.child_frame_id, round(x.translation.x, 12), round(x.translation.y, 12), round(x.translation.z, 12),
            round(x.rotation.x, 12), round(x.rotation.y, 12), round(x.rotation.z, 12), round(x.rotation.w, 12))


class Scene:
    """Replays /tf, /scene/static and /scene of one file in log-time order and checks the
    geometry in `world`. Feed every message with `add`, call `finish` at the end; `world_hand`
    and `ground_top` are what other files of the same run must share."""

    def __init__(self, window_start, level_hand=True):
        self.window_start = window_start  # log time -> True when it starts a design's window
        self.level_hand = level_hand  # require the hand level (off only to test the other checks)
        self.frames = {}  # child -> (parent, Rigid)
        self.pending = []  # (topic, message) at the current log time, drawn after its /tf
        self.now = None
        self.world_hand = None  # in the current window
        self.world_hands = set()
        self.ground_top = None
        self.stats = {"finger_points": 0, "lowest_finger_z": math.inf, "objects": 0, "object_poses": 0}

    def add(self, topic, t, msg):
        if self.now is not None and t != self.now:
            self._draw()
        self.now = t
        if topic == "/tf":
            self._tf(t, msg)
        elif topic in ("/scene", "/scene/static"):
            self.pending.append((topic, msg))

    def finish(self):
        self._draw()
        if self.world_hand is None:
            raise ValueError("no world -> hand transform in the file")
        return self.stats

    # -------------------------------------------------------------- transforms
    def _tf(self, t, msg):
        pairs = [(x.parent_frame_id, x.child_frame_id) for x in msg.transforms]
        if ("world", "hand") not in pairs:
            raise ValueError(f"/tf at {t}: no world -> hand (a viewer seeking here has no path from the scene to world)")
        for x in msg.transforms:
            if x.timestamp.seconds * 1_000_000_000 + x.timestamp.nanos != t:
                raise ValueError(f"/tf at {t}: stamp of {x.parent_frame_id} -> {x.child_frame_id} differs from the log time")
            q = x.rotation
            if abs(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w - 1.0) > 1e-9:
                raise ValueError(f"/tf at {t}: {x.parent_frame_id} -> {x.child_frame_id} rotation is not a unit quaternion")
            self.frames[x.child_frame_id] = (x.parent_frame_id, Rigid.of_pose(x.translation, x.rotation))
            if (x.parent_frame_id, x.child_frame_id) == ("world", "hand"):
                key = transform_key(x)
                if self.level_hand and abs(self.frames["hand"][1].r[2][2] - 1.0) > UPRIGHT_TOL:
                    raise ValueError(f"/tf at {t}: the hand is not level (its z axis is not world z)")
                if self.world_hand is None or self.window_start(t):
                    self.world_hand = key
                elif key != self.world_hand:
                    raise ValueError(f"/tf at {t}: world -> hand changed within a design's window ({key} vs {self.world_hand})")
                self.world_hands.add(key)
        if "object" in self.frames and any(p[1] == "object" for p in pairs):
            # checked once the entities of this instant are drawn: a window's first /tf may
            # come before its /scene/static, which says which object this window draws
            self.object_moved = t

    def to_world(self, frame, t):
        """The transform world <- frame at the current time, composed from the latest /tf."""
        out, seen = Rigid(), set()
        while frame != "world":
            if frame in seen or frame not in self.frames:
                raise ValueError(f"at {t}: frame {frame!r} has no transform path to world")
            seen.add(frame)
            parent, rigid = self.frames[frame]
            out = rigid.then(out)
            frame = parent
        return out

    # -------------------------------------------------------------- entities
    def _draw(self):
        t, pending = self.now, self.pending
        self.pending = []
        self._draw_entities(t, pending)
        if getattr(self, "object_moved", None) is not None:
            self._object_frame_above_ground(self.object_moved)
            self.object_moved = None

    def _draw_entities(self, t, pending):
        for topic, msg in pending:
            for e in msg.entities:
                if not e.frame_locked:
                    raise ValueError(f"{topic} at {t}: entity {e.id!r} is not frame_locked (a viewer keeps it where its frame was at the message time)")
                if e.id == "ground":
                    self._ground(t, e)
            for e in msg.entities:
                world_e = self.to_world(e.frame_id, t)
                for line in e.lines:
                    self._line_above_ground(t, e, world_e, line)
                if e.id == "object" and self.window_start(t):
                    self._object_standing(t, e, world_e)

    def _ground(self, t, e):
        if len(e.cubes) != 1:
            raise ValueError(f"at {t}: the ground must be one cube")
        c = e.cubes[0]
        top = self.to_world(e.frame_id, t).then(Rigid.of_pose(c.pose.position, c.pose.orientation))
        if abs(top.r[2][2] - 1.0) > UPRIGHT_TOL:
            raise ValueError(f"at {t}: the ground cube is not level")
        z = top.apply([0.0, 0.0, c.size.z / 2])[2]
        if self.ground_top is None:
            self.ground_top = z
        elif abs(z - self.ground_top) > 1e-12:
            raise ValueError(f"at {t}: the ground plane moved from z = {self.ground_top} to {z}")

    def _line_above_ground(self, t, e, world_e, line):
        if self.ground_top is None:
            raise ValueError(f"at {t}: {e.id!r} drawn before any ground")
        w = world_e.then(Rigid.of_pose(line.pose.position, line.pose.orientation))
        half = line.thickness / 2 if not line.scale_invariant else 0.0
        for p in line.points:
            z = w.apply([p.x, p.y, p.z])[2] - half
            self.stats["finger_points"] += 1
            self.stats["lowest_finger_z"] = min(self.stats["lowest_finger_z"], z - self.ground_top)
            if z < self.ground_top - GROUND_TOL:
                raise ValueError(f"at {t}: a point of {e.id!r} is {(self.ground_top - z) * 1e3:.3f} mm below the ground plane")

    def _object_standing(self, t, e, world_e):
        if len(e.cylinders) != 1:
            raise ValueError(f"at {t}: the object must be one cylinder")
        c = e.cylinders[0]
        w = world_e.then(Rigid.of_pose(c.pose.position, c.pose.orientation))
        axis_z = w.r[2][2]
        if abs(axis_z - 1.0) > UPRIGHT_TOL:
            raise ValueError(f"at {t}: the object is not upright at its window start (axis . z = {axis_z:.9f}): it must stand on the ground")
        base = w.apply([0.0, 0.0, -c.size.z / 2])[2]
        if abs(base - self.ground_top) > BASE_TOL:
            raise ValueError(f"at {t}: the object's base is {(base - self.ground_top) * 1e3:.3f} mm above the ground plane at its window start (it must stand on it)")
        self.stats["objects"] += 1
        self.object_shape = (c.size.x / 2, c.size.z, Rigid.of_pose(c.pose.position, c.pose.orientation))

    def _object_frame_above_ground(self, t):
        shape = getattr(self, "object_shape", None)
        if shape is None or self.ground_top is None:
            return
        radius, length, local = shape
        w = self.to_world("object", t).then(local)
        # the lowest point of the base rim: axis a, base centre b; rim point b + R u, u ⊥ a
        a = [w.r[0][2], w.r[1][2], w.r[2][2]]
        b = w.apply([0.0, 0.0, -length / 2])
        horizontal = math.sqrt(max(0.0, 1.0 - a[2] * a[2]))
        lowest = b[2] - radius * horizontal
        top_lowest = w.apply([0.0, 0.0, length / 2])[2] - radius * horizontal
        self.stats["object_poses"] += 1
        if min(lowest, top_lowest) < self.ground_top - PENETRATION_TOL:
            raise ValueError(f"at {t}: the object's rim is {(self.ground_top - min(lowest, top_lowest)) * 1e3:.3f} mm below the ground plane")
