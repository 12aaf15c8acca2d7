"""The re-fit objective of one level: E = alpha Ed + beta Es + gamma Ea (Eqs. 5-8), with
analytic first derivatives and the Gauss-Newton normal matrix.

Unknowns are the world positions ``x (P, 3)`` of every point of the original skeleton (joints,
frozen ones included, and end sites) per frame; the root stays at its original position. The
terms do not couple frames, so everything here is vectorised over a leading frame axis ``F``.

- Ed (Eq. 6): squared distance of every non-root point to its original position.
- Es (Eq. 7): squared change of the length between each kept point and its nearest kept
  ancestor, against the key posture ("frame 0"). Extension: also between kept children of one
  kept joint (siblings, a minimal set, see _rigid_set), because the output skeleton moves them
  as one rigid body; without it a parent's rotation could not reproduce its children's
  optimised positions. Pairs at zero key length (a BVH joint at its parent's position) use the
  vector difference instead of the length, which is smooth there.
- Ea (Eq. 8): squared change of cos theta_r (Eq. 4), the angle at each frozen joint r between
  its parent bone and each child bone, against the key posture.

Lengths are divided by a length scale ``L`` (the key posture's extent) so that the weights mean
the same for an asset in metres or centimetres: Ed and Es are unit-free like Ea.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import rotations
from .analysis import ZERO_LENGTH
from .frozen import FrozenLevel

# A rigid group's child whose height over its base plane is below this fraction of its distance
# to the parent (about 3 degrees) is held by its height (a flat quad), not by distances alone.
_FLAT = 0.05


@dataclass(frozen=True)
class Weights:
    """alpha, beta, gamma of Eq. 5 (the paper uses 0.2, 0.4, 0.4)."""

    distance: float = 0.2
    string: float = 0.4
    angle: float = 0.4

    def __post_init__(self) -> None:
        for name, value in (("distance", self.distance), ("string", self.string), ("angle", self.angle)):
            if not (np.isfinite(value) and value >= 0.0):
                raise ValueError(f"weights: {name} must be a finite non-negative number, got {value}")
        if self.distance <= 0.0:
            raise ValueError("weights: distance must be positive, or the re-fit has no unique optimum")


@dataclass(frozen=True)
class RefitProblem:
    """Static structure of one level's per-frame problem.

    Attributes
    ----------
    point_count : P, points of the original skeleton (joints and end sites).
    length_pairs : (Np, 2) int64 point pairs whose length is held (Es), child side first.
    key_lengths : (Np,) float64 their lengths in the key posture, b(0).
    bone_pair : (Np,) bool True for Eq. 7's kept-joint-to-kept-ancestor pairs (the bones whose
        lengths Fig. 7 measures), False for the sibling extension.
    coincident_pairs : (Nc, 2) int64 pairs at zero key length, held together as vectors.
    handed_quads : (Nh, 4) int64 (parent, three kept children) whose key posture is not flat:
        lengths fix such a group only up to a mirror image, which no rotation reproduces, so
        the hard option also keeps the sign of their volume.
    key_volumes : (Nh,) float64 the signed volumes det[a - p, b - p, c - p] in the key posture.
    flat_quads : (Nf, 4) int64 (parent, a, b, child) of a rigid group whose child lies nearly in
        the plane of the parent and the two base children: distances pin such a child out of
        that plane only to second order (the procedural humanoid's chest and neck, a hand and
        its finger bases), so the hard option holds its height over the plane instead of its
        distance to one of the base children.
    flat_volumes : (Nf,) float64 their key volumes det[a - p, b - p, c - p].
    flat_areas : (Nf,) float64 |(a - p) x (b - p)| in the key posture: the volume over it is the
        child's height over the plane.
    angle_triples : (Na, 3) int64 (parent, frozen joint, child) for Ea.
    key_cosines : (Na,) float64 cos theta_r in the key posture.
    weights : alpha, beta, gamma.
    length_scale : L in the asset's units.
    """

    point_count: int
    length_pairs: np.ndarray
    key_lengths: np.ndarray
    bone_pair: np.ndarray
    coincident_pairs: np.ndarray
    handed_quads: np.ndarray
    key_volumes: np.ndarray
    angle_triples: np.ndarray
    key_cosines: np.ndarray
    weights: Weights
    length_scale: float
    flat_quads: np.ndarray = field(default_factory=lambda: np.zeros((0, 4), np.int64))
    flat_volumes: np.ndarray = field(default_factory=lambda: np.zeros(0))
    flat_areas: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def variable_count(self) -> int:
        """3 (P - 1): every point but the root."""
        return 3 * (self.point_count - 1)

    @property
    def constraint_count(self) -> int:
        """Equalities of the hard option: one per held length, three per zero-length pair, one per
        flat quad."""
        return self.length_pairs.shape[0] + 3 * self.coincident_pairs.shape[0] + self.flat_quads.shape[0]


def _cosines(x: np.ndarray, triples: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """cos theta at the middle point of each triple (Eq. 4) and its gradients.

    Returns ``cos (F, Na)`` and the gradients with respect to the parent, joint and child
    points, each ``(F, Na, 3)``.
    """
    u = x[:, triples[:, 0]] - x[:, triples[:, 1]]
    v = x[:, triples[:, 2]] - x[:, triples[:, 1]]
    nu = np.linalg.norm(u, axis=-1, keepdims=True)
    nv = np.linalg.norm(v, axis=-1, keepdims=True)
    cos = np.sum(u * v, axis=-1, keepdims=True) / (nu * nv)
    d_u = v / (nu * nv) - cos * u / nu**2
    d_v = u / (nu * nv) - cos * v / nv**2
    return cos[..., 0], (d_u, -(d_u + d_v), d_v)


def _lengths(x: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lengths ``(F, Np)`` of the pairs and their unit directions ``(F, Np, 3)`` (0 at length 0)."""
    d = x[:, pairs[:, 0]] - x[:, pairs[:, 1]]
    length = np.linalg.norm(d, axis=-1)
    unit = np.divide(d, length[..., None], out=np.zeros_like(d), where=length[..., None] > 0.0)
    return length, unit


def _volumes(x: np.ndarray, quads: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """Signed volumes ``det[a - p, b - p, c - p]`` ``(F, Nh)`` of (p, a, b, c) quads and their
    gradients with respect to p, a, b, c, each ``(F, Nh, 3)``."""
    u = x[:, quads[:, 1]] - x[:, quads[:, 0]]
    v = x[:, quads[:, 2]] - x[:, quads[:, 0]]
    w = x[:, quads[:, 3]] - x[:, quads[:, 0]]
    d_u, d_v, d_w = rotations.cross(v, w), rotations.cross(w, u), rotations.cross(u, v)
    return np.sum(u * d_u, axis=-1), (-(d_u + d_v + d_w), d_u, d_v, d_w)


def _scatter(point_count: int, indices: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Sum ``values (F, N, 3)`` into points ``indices (N,)``, giving ``(F, P, 3)``."""
    incidence = np.zeros((point_count, indices.size))
    incidence[indices, np.arange(indices.size)] = 1.0
    return incidence @ values


def objective(problem: RefitProblem, x: np.ndarray, original: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """E (Eq. 5) per frame and its gradient.

    Parameters
    ----------
    x : (F, P, 3) candidate positions; row 0 (the root) is ignored and held at ``original``.
    original : (F, P, 3) original positions x^o.

    Returns
    -------
    value : (F,) E per frame.
    gradient : (F, P, 3) dE/dx, zero for the root.
    """
    w = problem.weights
    scale2 = problem.length_scale**2
    p = problem.point_count
    delta = x - original
    delta[:, 0] = 0.0
    value = w.distance / scale2 * np.sum(delta**2, axis=(1, 2))  # Ed, Eq. 6
    gradient = 2.0 * w.distance / scale2 * delta

    pairs = problem.length_pairs
    if pairs.size:  # Es, Eq. 7
        length, unit = _lengths(x, pairs)
        excess = length - problem.key_lengths
        value = value + w.string / scale2 * np.sum(excess**2, axis=1)
        pull = 2.0 * w.string / scale2 * excess[..., None] * unit
        gradient += _scatter(p, pairs[:, 0], pull) - _scatter(p, pairs[:, 1], pull)
    together = problem.coincident_pairs
    if together.size:  # Es at zero key length
        d = x[:, together[:, 0]] - x[:, together[:, 1]]
        value = value + w.string / scale2 * np.sum(d**2, axis=(1, 2))
        pull = 2.0 * w.string / scale2 * d
        gradient += _scatter(p, together[:, 0], pull) - _scatter(p, together[:, 1], pull)
    triples = problem.angle_triples
    if triples.size:  # Ea, Eq. 8
        cos, grads = _cosines(x, triples)
        excess = cos - problem.key_cosines
        value = value + w.angle * np.sum(excess**2, axis=1)
        for column, grad in enumerate(grads):
            gradient += _scatter(p, triples[:, column], 2.0 * w.angle * excess[..., None] * grad)
    gradient[:, 0] = 0.0
    return value, gradient


def _cosine_hessians(x: np.ndarray, triples: np.ndarray) -> np.ndarray:
    """Second derivatives of cos theta (Eq. 4) in (parent, joint, child) coordinates, ``(F, Na, 9, 9)``."""
    u = x[:, triples[:, 0]] - x[:, triples[:, 1]]
    v = x[:, triples[:, 2]] - x[:, triples[:, 1]]
    nu = np.linalg.norm(u, axis=-1)[..., None, None]
    nv = np.linalg.norm(v, axis=-1)[..., None, None]
    cos = (np.sum(u * v, axis=-1)[..., None, None]) / (nu * nv)
    g_u = v[..., :, None] / (nu * nv) - cos * u[..., :, None] / nu**2  # column vectors
    g_v = u[..., :, None] / (nu * nv) - cos * v[..., :, None] / nv**2
    eye = np.eye(3)

    def outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return a @ np.swapaxes(b, -1, -2)

    uc, vc = u[..., :, None], v[..., :, None]
    h_uu = -outer(vc, uc) / (nu**3 * nv) - (outer(uc, g_u) + cos * eye) / nu**2 + 2.0 * cos * outer(uc, uc) / nu**4
    h_vv = -outer(uc, vc) / (nv**3 * nu) - (outer(vc, g_v) + cos * eye) / nv**2 + 2.0 * cos * outer(vc, vc) / nv**4
    h_uv = eye / (nu * nv) - outer(vc, vc) / (nu * nv**3) - outer(uc, g_v) / nu**2
    h_uu = 0.5 * (h_uu + np.swapaxes(h_uu, -1, -2))
    h_vv = 0.5 * (h_vv + np.swapaxes(h_vv, -1, -2))
    # u = x_parent - x_joint, v = x_child - x_joint: map (u, v) to the three points.
    du = np.array([1.0, -1.0, 0.0])
    dv = np.array([0.0, -1.0, 1.0])
    blocks = (
        np.einsum("i,j->ij", du, du)[..., None, None] * h_uu[..., None, None, :, :]
        + np.einsum("i,j->ij", dv, dv)[..., None, None] * h_vv[..., None, None, :, :]
        + np.einsum("i,j->ij", du, dv)[..., None, None] * h_uv[..., None, None, :, :]
        + np.einsum("i,j->ij", dv, du)[..., None, None] * np.swapaxes(h_uv, -1, -2)[..., None, None, :, :]
    )  # (F, Na, 3 points, 3 points, 3, 3)
    return blocks.transpose(0, 1, 2, 4, 3, 5).reshape(x.shape[0], triples.shape[0], 9, 9)


def half_hessian(problem: RefitProblem, x: np.ndarray) -> np.ndarray:
    """Half the exact Hessian of E over the non-root points, ``(F, 3(P-1), 3(P-1))``.

    For each squared residual w r^2 the block is w (grad r grad r^T + r Hess r): the first part
    is the Gauss-Newton matrix, the second the curvature of the lengths and cosines, which plain
    Gauss-Newton drops and which makes it crawl when a frozen joint bends a chain hard. Can be
    indefinite; the solver damps it. O(pairs + triples) Python steps, vectorised over frames.
    """
    w = problem.weights
    scale2 = problem.length_scale**2
    frames, p = x.shape[0], problem.point_count
    h = np.zeros((frames, p, 3, p, 3))
    eye = np.eye(3)
    diagonal = np.arange(p)
    h[:, diagonal, :, diagonal, :] += w.distance / scale2 * eye

    def add_pair(a: int, b: int, block: np.ndarray) -> None:
        h[:, a, :, a, :] += block
        h[:, b, :, b, :] += block
        h[:, a, :, b, :] -= block
        h[:, b, :, a, :] -= block

    if problem.length_pairs.size:
        length, unit = _lengths(x, problem.length_pairs)
        along = unit[..., :, None] * unit[..., None, :]
        stretch = (length - problem.key_lengths) / np.maximum(length, 1e-300)
        blocks = w.string / scale2 * (along + stretch[..., None, None] * (eye - along))
        for k, (a, b) in enumerate(problem.length_pairs):
            add_pair(a, b, blocks[:, k])
    for a, b in problem.coincident_pairs:
        add_pair(a, b, w.string / scale2 * eye)
    if problem.angle_triples.size:
        cos, grads = _cosines(x, problem.angle_triples)
        g = np.concatenate(grads, axis=-1)  # (F, Na, 9)
        curvature = (cos - problem.key_cosines)[..., None, None] * _cosine_hessians(x, problem.angle_triples)
        blocks = w.angle * (g[..., :, None] * g[..., None, :] + curvature)
        for k, triple in enumerate(problem.angle_triples):
            for i, pi in enumerate(triple):
                for j, pj in enumerate(triple):
                    h[:, pi, :, pj, :] += blocks[:, k, 3 * i : 3 * i + 3, 3 * j : 3 * j + 3]
    n = 3 * (p - 1)
    return np.ascontiguousarray(h[:, 1:, :, 1:, :].reshape(frames, n, n))


def rigidity_constraints(problem: RefitProblem, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hard equalities, scaled by 1/L, and their Jacobian: every length Es holds (bones and
    siblings) and every flat quad's height, so the kept points move exactly as the level's rigid
    skeleton can.

    Returns ``values (F, m)`` (zero when every pair has its key length; zero-length pairs give
    three rows, x_a - x_b; a flat quad (V - V0) / (A0 L), its child's height change) and
    ``jacobian (F, m, P, 3)``.
    """
    frames, p = x.shape[0], problem.point_count
    pairs = problem.length_pairs
    together = problem.coincident_pairs
    length, unit = _lengths(x, pairs)
    values = [(length - problem.key_lengths) / problem.length_scale]
    rows = np.zeros((frames, pairs.shape[0], p, 3))
    index = np.arange(pairs.shape[0])
    rows[:, index, pairs[:, 0]] = unit / problem.length_scale
    rows[:, index, pairs[:, 1]] = -unit / problem.length_scale
    jacobians = [rows]
    if together.size:
        values.append(((x[:, together[:, 0]] - x[:, together[:, 1]]) / problem.length_scale).reshape(frames, -1))
        rows = np.zeros((frames, together.shape[0], 3, p, 3))
        for k, (a, b) in enumerate(together):
            rows[:, k, :, a, :] = np.eye(3) / problem.length_scale
            rows[:, k, :, b, :] = -np.eye(3) / problem.length_scale
        jacobians.append(rows.reshape(frames, -1, p, 3))
    if problem.flat_quads.size:
        volumes, grads = _volumes(x, problem.flat_quads)
        scale = 1.0 / (problem.flat_areas * problem.length_scale)
        values.append((volumes - problem.flat_volumes) * scale)
        rows = np.zeros((frames, problem.flat_quads.shape[0], p, 3))
        index = np.arange(problem.flat_quads.shape[0])
        for column, grad in enumerate(grads):
            rows[:, index, problem.flat_quads[:, column]] += scale[:, None] * grad
        jacobians.append(rows)
    jacobian = np.concatenate(jacobians, axis=1)
    jacobian[:, :, 0] = 0.0
    return np.concatenate(values, axis=1), jacobian


def handedness_constraints(problem: RefitProblem, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inequalities ``<= 0`` keeping each handed quad on its key posture's side of flat.

    Returns ``values (F, Nh)`` (``-sign(V0) V / L^3``) and ``jacobian (F, Nh, P, 3)``.
    """
    frames, p = x.shape[0], problem.point_count
    volumes, grads = _volumes(x, problem.handed_quads)
    sign = -np.sign(problem.key_volumes) / problem.length_scale**3
    jacobian = np.zeros((frames, problem.handed_quads.shape[0], p, 3))
    index = np.arange(problem.handed_quads.shape[0])
    for column, grad in enumerate(grads):
        jacobian[:, index, problem.handed_quads[:, column]] += sign[:, None] * grad
    jacobian[:, :, 0] = 0.0
    return sign * volumes, jacobian


Pairs = list[tuple[int, int]]
Quads = list[tuple[int, int, int, int]]


def _rigid_set(
    parent: int, children: list[int], key: np.ndarray, tolerance: float
) -> tuple[Pairs, Pairs, Quads, Quads]:
    """The constraints that make a kept joint and its kept children one rigid body, none redundant.

    A child at the parent's position is tied to the parent, one at an earlier child's position
    to that child; the others (distinct points) get their bone to the parent (Eq. 7) and, when
    they span a plane with it, the two children spanning the largest triangle with the parent
    are tied to each other. Every further child c is pinned to that base by 3 constraints (3k - 3
    for k distinct children, the count of a rigid body's shape): away from the base's plane, its
    distances to both base children, plus a handedness quad (distances fix c only up to its
    mirror image); within _FLAT of that plane, where distances pin it out of the plane only to
    second order, its distance to one base child (the one making the larger triangle with c and
    the parent) and a flat quad holding its height over the plane. Children all on one line
    through the parent are tied the same way, without quads: their distances hold the line only
    to second order, but they make the set a rigid body, which the core's solve moves as one.

    Returns bone pairs, sibling pairs, handed quads and flat quads (parent, base a, base b, child).
    """
    bones, siblings, distinct = [], [], []
    for child in children:
        if np.linalg.norm(key[child] - key[parent]) <= tolerance:
            bones.append((child, parent))
            continue
        same = [d for d in distinct if np.linalg.norm(key[child] - key[d]) <= tolerance]
        if same:
            siblings.append((child, same[0]))
        else:
            distinct.append(child)
            bones.append((child, parent))
    if len(distinct) < 2:
        return bones, siblings, [], []
    arms = key[distinct] - key[parent]
    areas = np.linalg.norm(np.cross(arms[:, None], arms[None]), axis=-1)
    i, j = np.unravel_index(int(np.argmax(areas)), areas.shape)
    if areas[i, j] <= tolerance * float(np.linalg.norm(arms, axis=-1).max()):
        # All on one line through the parent (hips at +-x, a twist joint beside the next bone):
        # the bones alone let each child swing on its own.
        a, b = distinct[:2]
        return bones, siblings + [(b, a)] + [(c, d) for c in distinct[2:] for d in (a, b)], [], []
    ia, ib = min(i, j), max(i, j)
    a, b = distinct[ia], distinct[ib]
    normal = np.cross(key[a] - key[parent], key[b] - key[parent]) / areas[i, j]
    siblings.append((b, a))
    handed, flat = [], []
    for k, c in enumerate(distinct):
        if c in (a, b):
            continue
        if abs(float(normal @ arms[k])) > _FLAT * float(np.linalg.norm(arms[k])):
            siblings += [(c, a), (c, b)]
            handed.append((parent, a, b, c))
        else:
            siblings.append((c, a if areas[k, ia] >= areas[k, ib] else b))
            flat.append((parent, a, b, c))
    return bones, siblings, handed, flat


def build_problem(level: FrozenLevel, weights: Weights | None = None) -> RefitProblem:
    """The per-frame problem of a level: its Es pairs and Ea triples with key-posture targets."""
    weights = weights or Weights()
    skeleton = level.skeleton
    scale = level.length_scale()
    key = level.key_positions
    kept = level.kept_indices[1:]
    rigid = ~level.animated  # an animated translation has no fixed length to hold

    bones, siblings, quads, flat = [], [], [], []
    for parent in np.unique(level.kept_parent[kept]):
        group = [int(c) for c in kept if level.kept_parent[c] == parent and rigid[c]]
        rigid_set = _rigid_set(int(parent), group, key, ZERO_LENGTH * scale)
        bones += rigid_set[0]
        siblings += rigid_set[1]
        quads += [q for q in rigid_set[2] if abs(_volumes(key[None], np.array([q]))[0][0, 0]) > 1e-6 * scale**3]
        flat += rigid_set[3]
    pairs = np.array(bones + siblings, dtype=np.int64).reshape(-1, 2)
    is_bone = np.arange(pairs.shape[0]) < len(bones)
    lengths = np.linalg.norm(key[pairs[:, 0]] - key[pairs[:, 1]], axis=-1)
    coincident = lengths <= ZERO_LENGTH * scale
    quads_array = np.array(quads, dtype=np.int64).reshape(-1, 4)
    flat_array = np.array(flat, dtype=np.int64).reshape(-1, 4)
    base = np.cross(key[flat_array[:, 1]] - key[flat_array[:, 0]], key[flat_array[:, 2]] - key[flat_array[:, 0]])

    triples = []
    children = skeleton.children()
    offset_length = np.linalg.norm(level.key_translations, axis=-1)
    for joint in np.flatnonzero(level.frozen):
        if offset_length[joint] <= ZERO_LENGTH * scale:
            continue  # no parent bone, no angle
        triples += [
            (int(skeleton.parents[joint]), int(joint), child)
            for child in children[joint]
            if rigid[child] and offset_length[child] > ZERO_LENGTH * scale
        ]
    triples_array = np.array(triples, dtype=np.int64).reshape(-1, 3)
    cosines, _ = _cosines(key[None], triples_array)
    return RefitProblem(
        point_count=skeleton.joint_count,
        length_pairs=pairs[~coincident],
        key_lengths=lengths[~coincident],
        bone_pair=is_bone[~coincident],
        coincident_pairs=pairs[coincident],
        handed_quads=quads_array,
        key_volumes=_volumes(key[None], quads_array)[0][0],
        angle_triples=triples_array,
        key_cosines=cosines[0],
        weights=weights,
        length_scale=scale,
        flat_quads=flat_array,
        flat_volumes=_volumes(key[None], flat_array)[0][0],
        flat_areas=np.linalg.norm(base, axis=-1),
    )


def split_problem(problem: RefitProblem) -> tuple[list[tuple[np.ndarray, RefitProblem]], np.ndarray]:
    """Split E into the independent problems of groups of points its terms tie together.

    The root is fixed, so terms only couple non-root points: E is the sum of one problem per
    connected group (e.g. the legs and the upper body when the hips' children sit at the hips)
    and a point with no Es or Ea term has its original position as exact optimum. Solving the
    groups apart finds the same optimum at a fraction of the cost (a dense solve costs n^3).

    Returns ``[(points, sub_problem)]``, where ``points`` are original point indices with the
    root first and the sub-problem numbers its points by position in ``points``, and the
    isolated points (root excluded).
    """
    label = np.arange(problem.point_count)

    def find(point: int) -> int:
        while label[point] != point:
            label[point] = label[label[point]]
            point = label[point]
        return point

    triples, quads, flat = problem.angle_triples, problem.handed_quads, problem.flat_quads
    edges = [problem.length_pairs, problem.coincident_pairs, triples[:, :2], triples[:, 1:]]
    edges += [q[:, k : k + 2] for q in (quads, flat) for k in range(3)]
    coupled = np.zeros(problem.point_count, bool)
    for a, b in np.concatenate([e.reshape(-1, 2) for e in edges]):
        coupled[[a, b]] = True
        if a != 0 and b != 0:
            label[find(int(a))] = find(int(b))
    coupled[0] = False
    group_of = np.array([find(p) for p in range(problem.point_count)])
    result = []
    for group in np.unique(group_of[coupled]):
        points = np.concatenate([[0], np.flatnonzero(coupled & (group_of == group))])
        renumber = np.full(problem.point_count, -1, dtype=np.int64)
        renumber[points] = np.arange(points.size)

        # A term belongs to the group holding all its points.
        pairs, together, angles, handed, flat_held = (
            np.all(renumber[terms] >= 0, axis=1)
            for terms in (problem.length_pairs, problem.coincident_pairs, triples, quads, flat)
        )
        result.append(
            (
                points,
                RefitProblem(
                    point_count=points.size,
                    length_pairs=renumber[problem.length_pairs[pairs]].reshape(-1, 2),
                    key_lengths=problem.key_lengths[pairs],
                    bone_pair=problem.bone_pair[pairs],
                    coincident_pairs=renumber[problem.coincident_pairs[together]].reshape(-1, 2),
                    handed_quads=renumber[quads[handed]].reshape(-1, 4),
                    key_volumes=problem.key_volumes[handed],
                    angle_triples=renumber[triples[angles]].reshape(-1, 3),
                    key_cosines=problem.key_cosines[angles],
                    weights=problem.weights,
                    length_scale=problem.length_scale,
                    flat_quads=renumber[flat[flat_held]].reshape(-1, 4),
                    flat_volumes=problem.flat_volumes[flat_held],
                    flat_areas=problem.flat_areas[flat_held],
                ),
            )
        )
    isolated = np.flatnonzero(~coupled)
    return result, isolated[isolated != 0]
