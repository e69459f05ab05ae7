"""Distance queries to triangle meshes (3-D) and outlines (2-D), written once in the kernel language.

These functions compile like every shape's kernel (:mod:`ndpack.kernels.language`): with Numba for
the CPU (which the oracles' own NumPy-facing methods use too), as CUDA device functions, and for
Warp. The surface lives in the flat parameter array ``prm`` from offset ``o``, in coordinates
normalised to the unit box around it (so float32 keeps its precision); see
:mod:`ndpack.meshes.layout` for how it is written, summarised here:

- header ``prm[o : o + HEADER]``: node count, sign method (0 pseudo-normals, 1 winding number,
  2 even-odd crossings), scale ``s``, centre ``c`` (3 slots), far-field ratio squared, the
  absolute offsets of the node, element and winding blocks, the floats per element, and four
  slots for the id of a Warp ``wp.Mesh`` of the same triangles (16 bits each; see
  :data:`WARP_NEAREST`). A user point ``x`` is queried as ``q = (x - c) / s``.
- node ``k`` (``2 D + 2`` floats): box lower (D), box upper (D), ``first``, ``count`` as in
  :mod:`ndpack.meshes.bvh`.
- triangle ``k`` (``TRIANGLE`` floats, in leaf order): vertices a, b, c (9), then the
  angle-weighted pseudo-normals of its face (3), edges ab, bc, ca (9) and vertices a, b, c (9).
- segment ``k`` (``SEGMENT`` floats): ends a, b (4), then the pseudo-normals of the segment (2) and
  of its ends (4).
- winding data of node ``k`` (``WINDING`` floats, 3-D): area vector (3), area centroid (3), radius.

Two names are bound per dimension when a program is built (:func:`add_queries`): ``element_query``
(``triangle_query`` or ``segment_query``) and ``inside_measure`` (the winding number, or the
crossing parity), so the tree walk and :func:`surface_distance` are written once for both.
"""

# ruff: noqa: F821  (stack and point are supplied when a kernel is printed)

import math

HEADER = 15
#: Where the Warp mesh id sits in the header (four 16-bit pieces: exact in float32).
MESH_ID = 11
TRIANGLE = 30
SEGMENT = 10
WINDING = 7


def node_size(dim: int) -> int:
    """Floats per tree node: box lower and upper, first, count."""
    return 2 * dim + 2


def add_queries(program) -> str:
    """Add the surface queries of ``program.dim`` (2 or 3) to ``program``; returns the name of
    :func:`surface_distance` (:func:`add_gradient` adds the rest)."""
    if program.dim == 3:
        program.use(triangle_query, name="element_query")
        program.use(mesh_winding_number, name="inside_measure")
        program.warp_natives["nearest_element"] = WARP_NEAREST
    else:
        program.use(segment_query, name="element_query")
        program.use(outline_crossings, name="inside_measure")
    return program.use(surface_distance)


def add_interpreter_queries(program) -> str:
    """Add what the tape interpreter (:mod:`ndpack.kernels.tape`) needs to evaluate a surface
    leaf: the queries (:func:`add_queries`, whose distance's name it returns) and the gradient's
    functions its entries call. The mesh and outline leaves hand it to the tape."""
    name = add_queries(program)
    for function in (surface_feature, surface_distance_at, surface_slope):
        program.use(function)
    return name


def add_gradient(program, oracle, offset: int) -> None:
    """Give ``oracle`` (a surface at ``offset``, its queries added) the closed-form gradient:
    one tree walk finds the nearest element, which gives both the distance and its direction
    (see :meth:`ndpack.kernels.program.Program.add_gradient`)."""
    feature = program.define(f"def _(p, prm, hint: float, bound: float):\n"
                             f"    return {program.use(surface_feature)}(p, prm, {offset}, hint, bound)\n")
    at = program.define(
        f"def _(p, prm, f: float):\n    return {program.use(surface_distance_at)}(p, prm, {offset}, f)\n")
    slope = program.define(f"def _(p, prm, f: float, value: float, k: int):\n"
                           f"    return {program.use(surface_slope)}(p, prm, {offset}, f, value, k)\n")
    program.add_gradient(oracle, feature, at, slope)


# [node box lower (D), upper (D)] at b: squared distance from q to the box (0 inside).
def box_squared_distance(q, prm, b: int):
    s = 0.0
    for i in range(D):
        t = max(prm[b + i] - q[i], q[i] - prm[b + D + i], 0.0)
        s += t * t
    return s


# [triangle at t]: the closest point of the triangle to q (Ericson's regions), then by ``want``:
# 0 its squared distance, 1 the offset q - closest along the pseudo-normal of the feature it
# lies on (negative inside a closed, outward-oriented mesh), 2, 3, 4 its x, y, z coordinate.
def triangle_query(q, prm, t: int, want: int):
    abx = prm[t + 3] - prm[t]
    aby = prm[t + 4] - prm[t + 1]
    abz = prm[t + 5] - prm[t + 2]
    acx = prm[t + 6] - prm[t]
    acy = prm[t + 7] - prm[t + 1]
    acz = prm[t + 8] - prm[t + 2]
    apx = q[0] - prm[t]
    apy = q[1] - prm[t + 1]
    apz = q[2] - prm[t + 2]
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    bpx = q[0] - prm[t + 3]
    bpy = q[1] - prm[t + 4]
    bpz = q[2] - prm[t + 5]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    cpx = q[0] - prm[t + 6]
    cpy = q[1] - prm[t + 7]
    cpz = q[2] - prm[t + 8]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4
    # The closest point is a + v * ab + w * ac, on the feature whose pseudo-normal is at n.
    v = 0.0
    w = 0.0
    n = t + 21
    if d1 <= 0.0 and d2 <= 0.0:
        n = t + 21
    elif d3 >= 0.0 and d4 <= d3:
        v = 1.0
        n = t + 24
    elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3) if d1 > d3 else 0.0
        n = t + 12
    elif d6 >= 0.0 and d5 <= d6:
        w = 1.0
        n = t + 27
    elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6) if d2 > d6 else 0.0
        n = t + 18
    elif va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6)) if (d4 - d3) + (d5 - d6) > 0.0 else 0.0
        v = 1.0 - w
        n = t + 15
    elif va + vb + vc > 0.0:
        v = vb / (va + vb + vc)
        w = vc / (va + vb + vc)
        n = t + 9
    ox = apx - v * abx - w * acx
    oy = apy - v * aby - w * acy
    oz = apz - v * abz - w * acz
    if want == 0:
        return ox * ox + oy * oy + oz * oz
    if want == 1:
        return ox * prm[n] + oy * prm[n + 1] + oz * prm[n + 2]
    if want == 2:
        return q[0] - ox
    if want == 3:
        return q[1] - oy
    return q[2] - oz


# The element nearest to q closer than sqrt(limit) (squared, normalised units), or -1.
# Closest child first, so the best distance shrinks early and prunes most of the tree.
def nearest_element(q, prm, o: int, limit: float):
    nodes = int(prm[o + 7])
    elements = int(prm[o + 8])
    stride = int(prm[o + 10])
    size = 2 * D + 2
    best = limit
    found = -1
    pending = stack()
    pending[0] = 0
    top = 1
    while top > 0:
        top -= 1
        node = pending[top]
        b = nodes + size * node
        if box_squared_distance(q, prm, b) >= best:
            continue
        count = int(prm[b + 2 * D + 1])
        if count > 0:
            start = int(prm[b + 2 * D])
            for k in range(start, start + count):
                d = element_query(q, prm, elements + stride * k, 0)
                if d < best:
                    best = d
                    found = k
        else:
            left = node + 1
            right = int(prm[b + 2 * D])
            near_left = box_squared_distance(q, prm, nodes + size * left)
            near_right = box_squared_distance(q, prm, nodes + size * right)
            # Push the farther child first, so the nearer is visited next.
            if near_left <= near_right:
                if near_right < best:
                    pending[top] = right
                    top += 1
                if near_left < best:
                    pending[top] = left
                    top += 1
            else:
                if near_left < best:
                    pending[top] = left
                    top += 1
                if near_right < best:
                    pending[top] = right
                    top += 1
    return found


# The solid angle of triangle t seen from q (Van Oosterom and Strackee), positive where q sees
# the triangle's back (inside an outward-oriented surface).
def triangle_solid_angle(q, prm, t: int):
    ax = prm[t] - q[0]
    ay = prm[t + 1] - q[1]
    az = prm[t + 2] - q[2]
    bx = prm[t + 3] - q[0]
    by = prm[t + 4] - q[1]
    bz = prm[t + 5] - q[2]
    cx = prm[t + 6] - q[0]
    cy = prm[t + 7] - q[1]
    cz = prm[t + 8] - q[2]
    la = math.sqrt(ax * ax + ay * ay + az * az)
    lb = math.sqrt(bx * bx + by * by + bz * bz)
    lc = math.sqrt(cx * cx + cy * cy + cz * cz)
    det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    den = la * lb * lc + (ax * bx + ay * by + az * bz) * lc + (ax * cx + ay * cy + az * cz) * lb
    den += (bx * cx + by * cy + bz * cz) * la
    return 2.0 * math.atan2(det, den)


# The generalised winding number of the mesh at q (Barill et al. 2018, first order): a node far
# from q (distance above ratio * radius) counts as one dipole, nearer ones open up.
def mesh_winding_number(q, prm, o: int):
    nodes = int(prm[o + 7])
    triangles = int(prm[o + 8])
    winding = int(prm[o + 9])
    ratio_squared = prm[o + 6]
    total = 0.0
    pending = stack()
    pending[0] = 0
    top = 1
    while top > 0:
        top -= 1
        node = pending[top]
        w = winding + 7 * node
        dx = prm[w + 3] - q[0]
        dy = prm[w + 4] - q[1]
        dz = prm[w + 5] - q[2]
        r2 = dx * dx + dy * dy + dz * dz
        if r2 > ratio_squared * prm[w + 6] * prm[w + 6]:
            total += (prm[w] * dx + prm[w + 1] * dy + prm[w + 2] * dz) / (r2 * math.sqrt(r2))
            continue
        b = nodes + 8 * node
        count = int(prm[b + 7])
        if count > 0:
            start = int(prm[b + 6])
            for k in range(start, start + count):
                total += triangle_solid_angle(q, prm, triangles + 30 * k)
        else:
            pending[top] = int(prm[b + 6])
            pending[top + 1] = node + 1
            top += 2
    return total / (4.0 * math.pi)


# Warp in float32 finds the nearest triangle with its own BVH (wp.Mesh, built by the Warp backend
# from the same triangles in the same order, so face k is triangle k); the distance and the sign
# then come from the triangle data as on every other backend.
WARP_NEAREST = """@wp.func
def nearest_element(q: Any, prm: wp.array(dtype=wp.float32), o: int, limit: wp.float32):
    mesh = wp.uint64(0)
    for k in range(4):
        mesh = mesh | (wp.uint64(int(prm[o + 11 + k])) << wp.uint64(16 * k))
    hit = wp.mesh_query_point_no_sign(mesh, wp.vec3(q[0], q[1], q[2]), wp.sqrt(limit))
    if hit.result:
        return wp.float32(hit.face)
    return wp.float32(-1.0)"""


# [segment at t] (D = 2): as triangle_query, for the closest point of the segment.
def segment_query(q, prm, t: int, want: int):
    abx = prm[t + 2] - prm[t]
    aby = prm[t + 3] - prm[t + 1]
    apx = q[0] - prm[t]
    apy = q[1] - prm[t + 1]
    s = (apx * abx + apy * aby) / (abx * abx + aby * aby)
    n = t + 4
    if s <= 0.0:
        s = 0.0
        n = t + 6
    elif s >= 1.0:
        s = 1.0
        n = t + 8
    ox = apx - s * abx
    oy = apy - s * aby
    if want == 0:
        return ox * ox + oy * oy
    if want == 1:
        return ox * prm[n] + oy * prm[n + 1]
    if want == 2:
        return q[0] - ox
    return q[1] - oy


# The even-odd rule (D = 2): 1 where a ray from q towards +x crosses an odd number of segments,
# else 0. Only nodes whose box meets the ray are opened; each segment is tested exactly as
# ndpack.shapes.polygon tests it, so both agree on every point.
def outline_crossings(q, prm, o: int):
    nodes = int(prm[o + 7])
    segments = int(prm[o + 8])
    x = q[0]
    y = q[1]
    crossings = 0
    pending = stack()
    pending[0] = 0
    top = 1
    while top > 0:
        top -= 1
        node = pending[top]
        b = nodes + 6 * node
        if prm[b + 1] > y or prm[b + 3] < y or prm[b + 2] < x:
            continue
        count = int(prm[b + 5])
        if count > 0:
            start = int(prm[b + 4])
            for k in range(start, start + count):
                t = segments + 10 * k
                sx = prm[t]
                sy = prm[t + 1]
                ey = prm[t + 3]
                edge_x = prm[t + 2] - sx
                edge_y = ey - sy
                above_start = 1 if sy > y else 0
                above_end = 1 if ey > y else 0
                if above_start != above_end:
                    left = 1 if edge_x * (y - sy) - (x - sx) * edge_y > 0.0 else 0
                    upward = 1 if edge_y > 0.0 else 0
                    if left == upward:
                        crossings += 1
        else:
            pending[top] = int(prm[b + 4])
            pending[top + 1] = node + 1
            top += 2
    return crossings % 2


# The element of the surface at o nearest to p (user units), as a float: the feature that
# surface_distance_at and surface_slope take (one tree walk serves the distance and its gradient).
# Two bounds prune the walk without changing its answer. ``hint`` (>= 0), an element found near p
# before (the last step's): the nearest is no farther than it. ``bound``: only an element nearer
# than that matters (-2 when there is none); on a closed surface (pseudo-normal or crossing sign)
# a caller that has an inserted sphere ``bound`` away knows then that p lies inside, farther than
# ``bound`` from the boundary (the way to the sphere would cross the surface otherwise). Winding
# numbers have no such guarantee across holes, so they ignore ``bound``. Both limits are widened
# by a relative slack above any rounding, so an element at exactly the limit is still found.
def surface_feature(p, prm, o: int, hint: float, bound: float):
    scale = prm[o + 2]
    q = point()
    for i in range(D):
        q[i] = (p[i] - prm[o + 3 + i]) / scale
    limit = 1.0e30
    if bound < 1.0e30 and prm[o + 1] != 1.0:
        b = max(bound, 0.0) / scale
        limit = b * b * 1.000001 + 1.0e-30
    if hint >= 0.0:
        d = element_query(q, prm, int(prm[o + 8]) + int(prm[o + 10]) * int(hint), 0)
        limit = min(limit, d * 1.000001 + 1.0e-30)
    found = nearest_element(q, prm, o, limit)
    if found < 0:
        return -2.0
    return float(found)


# The signed distance from p (user units) to the surface at o, whose nearest element is f:
# negative inside.
def surface_distance_at(p, prm, o: int, f: float):
    scale = prm[o + 2]
    q = point()
    for i in range(D):
        q[i] = (p[i] - prm[o + 3 + i]) / scale
    t = int(prm[o + 8]) + int(prm[o + 10]) * int(f)
    unsigned = math.sqrt(element_query(q, prm, t, 0)) * scale
    if prm[o + 1] == 0.0:
        if element_query(q, prm, t, 1) < 0.0:
            return -unsigned
        return unsigned
    if inside_measure(q, prm, o) > 0.5:
        return -unsigned
    return unsigned


# The signed distance from p (user units) to the surface at o: negative inside.
def surface_distance(p, prm, o: int):
    return surface_distance_at(p, prm, o, surface_feature(p, prm, o, -1.0, 1.0e30))


# Component k of the unit gradient of the signed distance at p, given p's nearest element f and
# signed distance value: along p less its closest point (outside), the opposite way inside, and
# the element's outward normal where p lies on the surface (the offset has no direction there).
def surface_slope(p, prm, o: int, f: float, value: float, k: int):
    scale = prm[o + 2]
    t = int(prm[o + 8]) + int(prm[o + 10]) * int(f)
    length = abs(value) / scale
    if length <= 1.0e-12:
        return prm[t + (9 if D == 3 else 4) + k]
    q = point()
    for i in range(D):
        q[i] = (p[i] - prm[o + 3 + i]) / scale
    offset = q[k] - element_query(q, prm, t, 2 + k)
    if value < 0.0:
        return -offset / length
    return offset / length
