"""Objects on the table: their specification, their physics body and their mesh.

An :class:`ObjectSpec` is plain data (it is what a layout file holds and what ground truth
records). ``build_object`` turns it into a SAPIEN rigid body whose mass follows from its
volume, and ``object_mesh`` into the triangle mesh the range camera sees. Both use the
same local frame: the body's origin at its centre, a cylinder's axis along local x (SAPIEN's
convention), standing up for ``cylinder`` and lying for ``lying-cylinder``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import open3d as o3d
import sapien
from afford.features.errors import DataError

__all__ = ["SHAPES", "SOLID_SHAPES", "HANDLE", "MUG_MIN_HEIGHT", "ObjectSpec", "box_mesh", "build_object", "object_mesh",
           "yaw_quaternion", "handle_boxes"]

#: The object shapes the scenes know, in the order ground truth stores them.
SHAPES = ("box", "cylinder", "lying-cylinder", "sphere", "mug")
#: The shapes of chapters 5-8 (what their scenes draw from): every shape but the mug.
SOLID_SHAPES = SHAPES[:4]

#: The mug's handle, the same on every mug (thesis 9.3.4: "only the handle dimension is kept
#: fixed"): how far it stands out from the wall, its height, the thickness of its bars and
#: its width, metres. Its opening is 3.3 cm deep and 4.6 cm high, room for one finger.
HANDLE = {"reach": 0.045, "height": 0.07, "bar": 0.012, "width": 0.02}
#: A mug is at least this tall, so that its handle fits on its side.
MUG_MIN_HEIGHT = 0.09

# Rotation of a cylinder's local frame so that its axis (x) points up (z).
_UPRIGHT = np.array([math.cos(-math.pi / 4), 0.0, math.sin(-math.pi / 4), 0.0])


def box_mesh(half) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of a box of half extents ``half`` about its centre (for the range sensors)."""
    h = np.asarray(half)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float) * h
    faces = np.array([
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
    ], dtype=np.uint32)
    return corners, faces


def yaw_quaternion(yaw_deg: float) -> np.ndarray:
    """Quaternion (w, x, y, z) of a rotation about the vertical axis."""
    half = math.radians(yaw_deg) / 2
    return np.array([math.cos(half), 0.0, 0.0, math.sin(half)])


@dataclass(frozen=True)
class ObjectSpec:
    """One object: what it is, how big, where it stands.

    Parameters
    ----------
    shape : str
        One of :data:`SHAPES`.
    size : tuple of float
        Metres: box edges (x, y, z in the object's frame), ``(diameter, length)`` for
        cylinders, ``(diameter,)`` for spheres.
    position : tuple of float
        ``(x, y)`` of the object's centre on the table top, robot frame.
    yaw : float
        Degrees about the vertical axis.
    held : bool
        The object starts grasped and lifted by the hand.
    """

    shape: str
    size: tuple[float, ...]
    position: tuple[float, float]
    yaw: float = 0.0
    held: bool = False

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise DataError(f"unknown shape {self.shape!r}; known shapes: {', '.join(SHAPES)}")
        want = {"box": 3, "cylinder": 2, "lying-cylinder": 2, "sphere": 1, "mug": 2}[self.shape]
        if len(self.size) != want:
            raise DataError(f"a {self.shape} needs {want} size value(s), got {len(self.size)}")
        if any(not (0.01 <= s <= 1.0) for s in self.size):
            raise DataError(f"object sizes must be between 0.01 and 1.0 m, got {list(self.size)}")
        if self.shape == "mug" and self.size[1] < MUG_MIN_HEIGHT - 1e-9:
            raise DataError(f"a mug must be at least {MUG_MIN_HEIGHT:.2f} m tall to carry its handle, "
                            f"got {self.size[1]}")
        if len(self.position) != 2:
            raise DataError("an object's position is [x, y] on the table")
        if not all(math.isfinite(v) for v in (*self.size, *self.position, self.yaw)):
            raise DataError("an object's size, position and yaw must be finite numbers")

    @property
    def extents(self) -> np.ndarray:
        """Full extents (x, y, z) in the object's own frame before yaw."""
        s = self.size
        if self.shape == "box":
            return np.array(s, dtype=float)
        if self.shape == "sphere":
            return np.array([s[0]] * 3, dtype=float)
        d, length = s
        if self.shape == "mug":  # the handle on local +x: bounded as if it stood out both ways
            return np.array([d + 2 * HANDLE["reach"], d, length], dtype=float)
        if self.shape == "cylinder":
            return np.array([d, d, length], dtype=float)
        return np.array([length, d, d], dtype=float)  # lying: axis along local x

    @property
    def half_footprint(self) -> tuple[float, float]:
        """Half extents (x, y) of the yawed object's axis-aligned footprint."""
        e = self.extents
        th = math.radians(self.yaw)
        c, s = abs(math.cos(th)), abs(math.sin(th))
        return (c * e[0] + s * e[1]) / 2, (s * e[0] + c * e[1]) / 2

    @property
    def height(self) -> float:
        return float(self.extents[2])

    @property
    def footprint_radius(self) -> float:
        """Half the diagonal of the object's footprint: how far it reaches from its centre."""
        e = self.extents
        return float(math.hypot(e[0], e[1]) / 2)

    @property
    def volume(self) -> float:
        s = self.size
        if self.shape == "box":
            return float(s[0] * s[1] * s[2])
        if self.shape == "sphere":
            return float(math.pi * s[0] ** 3 / 6)
        solid = float(math.pi * (s[0] / 2) ** 2 * s[1])
        if self.shape == "mug":
            solid += sum(float(np.prod(2 * np.asarray(h))) for _, h in handle_boxes(s[0]))
        return solid

    def to_dict(self) -> dict:
        return {"shape": self.shape, "size": list(self.size), "position": list(self.position),
                "yaw": self.yaw, "held": self.held}

    def pose(self, table_top: float) -> sapien.Pose:
        """Resting pose on the table top."""
        return sapien.Pose([self.position[0], self.position[1], table_top + self.height / 2],
                           yaw_quaternion(self.yaw))

    def _local_rotation(self) -> np.ndarray:
        return _UPRIGHT if self.shape in ("cylinder", "mug") else np.array([1.0, 0.0, 0.0, 0.0])


def handle_boxes(diameter: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The mug handle's three convex pieces as (centre, half extents) in the mug's frame
    (z up, the handle on +x): an upper and a lower arm from inside the wall outwards, and
    the bar that joins them."""
    r, h = diameter / 2, HANDLE
    arm_len = h["reach"] + 0.006
    half_arm = np.array([arm_len / 2, h["width"] / 2, h["bar"] / 2])
    arm_x = r - 0.006 + arm_len / 2
    zc = h["height"] / 2 - h["bar"] / 2
    bar = (np.array([r + h["reach"] - h["bar"] / 2, 0.0, 0.0]), np.array([h["bar"] / 2, h["width"] / 2, h["height"] / 2]))
    return [(np.array([arm_x, 0.0, zc]), half_arm), (np.array([arm_x, 0.0, -zc]), half_arm), bar]


@dataclass
class _Cache:
    meshes: dict = field(default_factory=dict)


_CACHE = _Cache()


#: Sides of the prism that stands for a cylinder, in physics and in the camera's mesh alike.
CYLINDER_SIDES = 32


def _prism(radius: float, length: float) -> np.ndarray:
    """Vertices of a CYLINDER_SIDES-gon prism along local x."""
    # Offset by half a facet: with a vertex straight down a lying cylinder would start
    # balanced on an edge and roll away at the least touch.
    a = np.linspace(0.0, 2 * math.pi, CYLINDER_SIDES, endpoint=False) + math.pi / CYLINDER_SIDES
    ring = np.column_stack([np.cos(a), np.sin(a)]) * radius
    ends = [np.column_stack([np.full(len(a), x), ring]) for x in (-length / 2, length / 2)]
    return np.concatenate(ends).astype(np.float32)


def build_object(scene: sapien.Scene, spec: ObjectSpec, table_top: float, density: float,
                 material: sapien.physx.PhysxMaterial) -> sapien.Entity:
    """Add the object's rigid body to ``scene``, resting on the table top.

    A cylinder is a 32-sided convex prism rather than PhysX's exact cylinder: on the exact
    one a lying cylinder that has just slid to rest starts rolling by itself (contact
    jitter with nothing to stop it), while the prism's narrow facets hold it still yet
    let it roll when pushed across its axis.
    """
    body = sapien.physx.PhysxRigidDynamicComponent()
    extra = []
    if spec.shape == "mug":  # one actor: the cup and its handle's three pieces
        for centre, half in handle_boxes(spec.size[0]):
            piece = sapien.physx.PhysxCollisionShapeBox(half_size=half, material=material)
            piece.local_pose = sapien.Pose(centre)
            extra.append(piece)
    if spec.shape == "box":
        shape = sapien.physx.PhysxCollisionShapeBox(half_size=np.array(spec.size) / 2, material=material)
    elif spec.shape == "sphere":
        shape = sapien.physx.PhysxCollisionShapeSphere(radius=spec.size[0] / 2, material=material)
    else:
        shape = sapien.physx.PhysxCollisionShapeConvexMesh(
            vertices=_prism(spec.size[0] / 2, spec.size[1]), scale=np.ones(3, dtype=np.float32), material=material)
        shape.local_pose = sapien.Pose(q=spec._local_rotation())
    for part in [shape, *extra]:
        part.set_density(density)
        body.attach(part)
    entity = sapien.Entity()
    entity.name = f"object-{spec.shape}"
    entity.add_component(body)
    entity.pose = spec.pose(table_top)
    scene.add_entity(entity)
    return entity


def object_mesh(spec: ObjectSpec) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (in the body frame) and triangles of the object's surface."""
    key = (spec.shape, tuple(spec.size))
    hit = _CACHE.meshes.get(key)
    if hit is not None:
        return hit
    if spec.shape == "box":
        mesh = o3d.geometry.TriangleMesh.create_box(*spec.size)
        mesh.translate(-np.array(spec.size) / 2)
    elif spec.shape == "sphere":
        mesh = o3d.geometry.TriangleMesh.create_sphere(radius=spec.size[0] / 2, resolution=16)
    elif spec.shape == "mug":
        mesh = o3d.geometry.TriangleMesh.create_cylinder(radius=spec.size[0] / 2, height=spec.size[1],
                                                         resolution=CYLINDER_SIDES, split=1)
        for centre, half in handle_boxes(spec.size[0]):
            piece = o3d.geometry.TriangleMesh.create_box(*(2 * half))
            piece.translate(centre - half)
            mesh += piece
    else:
        # Open3D's cylinder stands along z; rotate it onto the body's local axis.
        mesh = o3d.geometry.TriangleMesh.create_cylinder(radius=spec.size[0] / 2, height=spec.size[1],
                                                         resolution=CYLINDER_SIDES, split=1)
        if spec.shape == "lying-cylinder":
            mesh.rotate(o3d.geometry.get_rotation_matrix_from_xyz((0.0, math.pi / 2, 0.0)), center=(0, 0, 0))
    result = (np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.triangles, dtype=np.uint32))
    if len(_CACHE.meshes) > 512:
        _CACHE.meshes.clear()
    _CACHE.meshes[key] = result
    return result
