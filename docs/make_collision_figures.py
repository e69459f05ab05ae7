"""Draw docs/img/collision-link-8-32-128.png: a robot-arm link covered by 8, 32 and 128 spheres.

    python docs/make_collision_figures.py                       # numba backend
    python docs/make_collision_figures.py --out /tmp/link.png --samples 5000 --width 400

The part is made here from ndpack CSG rather than read from a file: a link 0.46 m long of the
kind a motion planner stands in for a few dozen spheres, with what makes such a cover hard (a
thin flat web, two bosses of different sizes, bores through them, sharp rims), known dimensions
(the protrusions below are in millimetres) and no data file needed. (The rocker-arm mesh would do
too, but its model has no units and the shared folder is not everywhere.)

Each covering is ``nd.cover(link, n=k, seed=0)``. The picture: the part ray-marched on its own
distance (grey, with a dark silhouette), and the covering spheres over it, translucent, each in
its own colour, with dark lines where two spheres' fronts meet; an orthographic camera, the same
framing in the three panels.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the checkout's ndpack, even when another is installed

import numpy as np  # noqa: E402

import ndpack as nd  # noqa: E402
from ndpack.pictures import camera_axes  # noqa: E402

OUT = HERE / "img" / "collision-link-8-32-128.png"
COUNTS = (8, 32, 128)
VIEW = (-60.0, 35.0)  # azimuth, elevation (degrees)
LIGHT = np.array([-0.45, 0.6, 0.66]) / np.linalg.norm([-0.45, 0.6, 0.66])  # camera coordinates
SPHERE_ALPHA = 0.38
PART_COLOUR = np.array([0.62, 0.64, 0.68])
MARGIN = 0.04
SUPERSAMPLE = 2


def robot_link():
    """A link 0.46 m long: a 0.12 m boss (bore 0.05 m) and a 0.09 m boss (bore 0.036 m), 0.08 m
    thick, joined by a flattened rod (a capsule 0.07 m across cut to 0.05 m thick)."""
    shoulder, elbow = np.array([0.06, 0.0, 0.0]), np.array([0.415, 0.0, 0.0])
    lift = np.array([0.0, 0.0, 0.04])
    bosses = nd.Cylinder(shoulder - lift, shoulder + lift, 0.06) | nd.Cylinder(elbow - lift, elbow + lift, 0.045)
    web = nd.Capsule(shoulder, elbow, 0.035) & nd.Slab([0, 0, 1], -0.025, 0.025)
    bores = (nd.Cylinder(shoulder - 1.5 * lift, shoulder + 1.5 * lift, 0.025)
             | nd.Cylinder(elbow - 1.5 * lift, elbow + 1.5 * lift, 0.018))
    return (bosses | web) - bores


# ------------------------------------------------------------------------------------------------ pictures
class Camera:
    """An orthographic camera framing the given spheres: a ray per pixel, from in front of them."""

    def __init__(self, centers, radii, width, view=VIEW):
        self.right, self.up, self.towards = camera_axes(*view)
        u, v, w = centers @ self.right, centers @ self.up, centers @ self.towards
        low = np.array([(u - radii).min(), (v - radii).min()])
        high = np.array([(u + radii).max(), (v + radii).max()])
        span = (high - low) * (1 + 2 * MARGIN)
        self.width = int(width)
        self.height = int(round(width * span[1] / span[0]))
        self.pixel = span[0] / self.width
        middle = 0.5 * (low + high)
        xs = middle[0] + (np.arange(self.width) + 0.5 - self.width / 2) * self.pixel
        ys = middle[1] - (np.arange(self.height) + 0.5 - self.height / 2) * self.pixel
        grid_x, grid_y = np.meshgrid(xs, ys)
        self.front = float((w + radii).max()) + 1e-3
        self.depth = self.front - float((w - radii).min()) + 1e-3
        self.origins = (grid_x[..., None] * self.right + grid_y[..., None] * self.up
                        + self.front * self.towards).reshape(-1, 3)
        self.direction = -self.towards

    def shade(self, normals):
        """Ambient + Lambert light from the upper left (camera coordinates), per normal."""
        camera = np.stack([normals @ self.right, normals @ self.up, normals @ self.towards], axis=-1)
        return 0.35 + 0.65 * np.clip(camera @ LIGHT, 0.0, 1.0)

    def image(self, values):
        return values.reshape(self.height, self.width, *values.shape[1:])


def march(shape, camera, steps=300):
    """Sphere-trace ``shape`` along the camera's rays: (hit mask, depth, normals), one per pixel."""
    count = len(camera.origins)
    t = np.zeros(count)
    hit = np.zeros(count, dtype=bool)
    active = np.arange(count)
    epsilon = 1e-4 * camera.pixel
    for _ in range(steps):
        if not len(active):
            break
        points = camera.origins[active] + t[active, None] * camera.direction
        distance = shape.distance(points)
        landed = distance < epsilon
        hit[active[landed]] = True
        t[active] += np.maximum(distance, 0.0)
        active = active[~landed & (t[active] < camera.depth)]
    normals = np.zeros((count, 3))
    if hit.any():
        gradient = shape.gradient(camera.origins[hit] + t[hit, None] * camera.direction)
        normals[hit] = gradient / np.linalg.norm(gradient, axis=1, keepdims=True)
    return hit, t, normals


def nearest_spheres(camera, centers, radii):
    """Per pixel, the sphere whose front the ray meets first (-1 for none), and the normal there."""
    count = len(camera.origins)
    best, which = np.full(count, np.inf), np.full(count, -1)
    for i, (centre, radius) in enumerate(zip(centers, radii)):
        offset = centre - camera.origins
        along = offset @ camera.direction
        miss = (offset ** 2).sum(axis=1) - along ** 2
        inside = miss < radius ** 2
        front = np.where(inside, along - np.sqrt(np.maximum(radius ** 2 - miss, 0.0)), np.inf)
        closer = front < best
        best[closer], which[closer] = front[closer], i
    normals = np.zeros((count, 3))
    hit = which >= 0
    front = camera.origins[hit] + best[hit, None] * camera.direction
    normals[hit] = (front - centers[which[hit]]) / radii[which[hit], None]
    return which, normals


def edges(labels):
    """Pixels whose label differs from a neighbour's (right or below)."""
    edge = np.zeros(labels.shape, dtype=bool)
    edge[:, :-1] |= labels[:, :-1] != labels[:, 1:]
    edge[:-1, :] |= labels[:-1, :] != labels[1:, :]
    return edge


def panel(camera, part, centers, radii, colours):
    """An RGB image (h, w, 3) in [0, 1]: the part, the spheres translucent over it, their seams and
    the part's silhouette."""
    hit, _, part_normals = part
    image = np.ones((len(camera.origins), 3))
    image[hit] = PART_COLOUR * camera.shade(part_normals[hit])[:, None]
    which, normals = nearest_spheres(camera, centers, radii)
    covered = which >= 0
    sphere = colours[which[covered] % len(colours)] * camera.shade(normals[covered])[:, None]
    image[covered] = SPHERE_ALPHA * sphere + (1 - SPHERE_ALPHA) * image[covered]
    image = camera.image(image)
    image[edges(camera.image(which))] *= 0.55
    image[edges(camera.image(hit))] = 0.1
    return image


def downsample(image, factor):
    h, w = image.shape[0] // factor * factor, image.shape[1] // factor * factor
    return image[:h, :w].reshape(h // factor, factor, w // factor, factor, -1).mean(axis=(1, 3))


def save_cache(path, coverings):
    arrays = {}
    for i, (centers, radii, title) in enumerate(coverings):
        arrays.update({f"centers{i}": centers, f"radii{i}": radii, f"title{i}": np.asarray(title)})
    np.savez(path, **arrays)


def load_cache(path):
    with np.load(path) as data:
        return [(data[f"centers{i}"], data[f"radii{i}"], str(data[f"title{i}"])) for i in range(len(COUNTS))]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--backend", default="numba")
    parser.add_argument("--samples", type=int, default=20_000, help="nd.cover's samples")
    parser.add_argument("--width", type=int, default=560, help="pixels across each panel")
    parser.add_argument("--cache", type=Path, help="keep the coverings in this .npz (and reuse them if it exists), "
                        "to redraw without covering again")
    args = parser.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    link = robot_link()
    coverings = load_cache(args.cache) if args.cache and args.cache.exists() else None
    if coverings is None:
        coverings = []
        for count in COUNTS:
            started = time.perf_counter()
            covering = nd.cover(link, n=count, samples=args.samples, seed=0, backend=args.backend, progress=False)
            print(f"{count} spheres ({time.perf_counter() - started:.1f} s): {covering.summary()}", flush=True)
            report = covering.report
            title = (f"{len(covering)} spheres: protrusion {1000 * report.max_protrusion:.1f} mm\n"
                     f"(mean {1000 * report.mean_protrusion:.1f} mm), "
                     f"{'all covered' if report.covered else 'NOT covered'}")
            coverings.append((covering.centers, covering.radii, title))
        if args.cache:
            save_cache(args.cache, coverings)
    centers = np.vstack([c[0] for c in coverings])
    radii = np.concatenate([c[1] for c in coverings])
    camera = Camera(centers, radii, SUPERSAMPLE * args.width)
    started = time.perf_counter()
    part = march(link, camera)
    print(f"part ray-marched in {time.perf_counter() - started:.1f} s", flush=True)
    colours = np.asarray(matplotlib.colormaps["tab10"].colors)[:, :3]
    figure, axes = plt.subplots(1, len(COUNTS), figsize=(4.2 * len(COUNTS), 4.2 * camera.height / camera.width + 0.6),
                                dpi=args.width / 4.2, layout="constrained")
    for ax, (centers, radii, title) in zip(axes, coverings):
        ax.imshow(np.clip(downsample(panel(camera, part, centers, radii, colours), SUPERSAMPLE), 0, 1))
        ax.set_title(title, fontsize=10)
        ax.set_axis_off()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
