"""Pictures: the ray-caster draws the right discs in the right order, slices and plots hold the
right circles, files are written, and mistakes are explained."""

import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.image
import numpy as np
import pytest

import ndpack as nd
from ndpack.pictures import (
    cast_spheres,
    choose_up,
    picture,
    plot,
    plot_fill,
    render,
    save_figure,
    save_fill_figure,
    slice_balls,
)
from ndpack.pictures.raycast import FRAME_MARGIN

WHITE = np.array([255, 255, 255])
MESH = Path(__file__).resolve().parents[1] / "data" / "meshes" / "cow.ply"


def spheres(centers, radii):
    """A packing of given spheres (no shape, no statistics), as loaded from a file."""
    centers = np.asarray(centers, dtype=np.float64)
    return nd.Packing(centers, np.asarray(radii, dtype=np.float64), np.zeros(len(centers), dtype=np.int64), 1.0)


def covered(image, background=WHITE):
    """(h, w) bool: pixels not of the background colour."""
    return np.any(image != background, axis=2)


# ---------------------------------------------------------------------------------------------- ray-caster
def test_one_sphere_is_a_disc_of_the_right_area_where_expected():
    # Azimuth 0, elevation 0: the camera looks along -x; screen right is +y, screen up is +z.
    # The frame (a unit ball at the origin) fixes the scale, so the small sphere's place is known.
    width, height = 240, 200
    image = cast_spheres([[0.0, 0.5, 0.25]], [0.2], [[0.2, 0.3, 0.6]], size=(width, height), view=(0, 0),
                         supersample=1, outline=False, occlusion=False, frame=([[0.0, 0.0, 0.0]], [1.0]))
    assert image.shape == (height, width, 3) and image.dtype == np.uint8
    scale = min(width, height) / 2 / (1 + 2 * FRAME_MARGIN)  # pixels per unit
    mask = covered(image)
    expected_area = np.pi * (0.2 * scale) ** 2
    assert mask.sum() == pytest.approx(expected_area, rel=0.03)
    rows, columns = np.nonzero(mask)
    assert columns.mean() + 0.5 == pytest.approx(width / 2 + 0.5 * scale, abs=0.5)
    assert rows.mean() + 0.5 == pytest.approx(height / 2 - 0.25 * scale, abs=0.5)


def test_shading_is_lit_from_the_upper_left():
    image = cast_spheres([[0.0, 0.0, 0.0]], [1.0], [[0.8, 0.8, 0.8]], size=(101, 101), view=(0, 0),
                         outline=False, occlusion=False).astype(int)
    upper_left, lower_right = image[30, 30].sum(), image[70, 70].sum()
    assert upper_left > lower_right + 100


def test_nearer_sphere_hides_the_farther_one():
    red, blue = [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]
    centers = [[1.0, 0.0, 0.0], [-1.0, 0.2, 0.0]]  # red nearer the camera at azimuth 0
    for order in ([0, 1], [1, 0]):  # the input order must not matter
        image = cast_spheres(np.array(centers)[order], [0.5, 0.5], np.array([red, blue])[order],
                             size=(120, 120), view=(0, 0), occlusion=False).astype(int)
        middle = image[60, 55]
        assert middle[0] > 2 * middle[2]
    # From the other side the blue sphere is in front.
    image = cast_spheres(centers, [0.5, 0.5], [red, blue], size=(120, 120), view=(180, 0), occlusion=False)
    middle = image[60, 65].astype(int)
    assert middle[2] > 2 * middle[0]


def test_clip_plane_removes_the_spheres_beyond_it():
    packing = spheres([[0.0, 0.0, 0.0], [0.0, 2.0, 0.0]], [0.5, 0.5])
    # up="z": the pair is 3x longer along y, which "auto" would stand up.
    whole = render(packing, size=(200, 100), view=(0, 0), occlusion=False, up="z")
    clipped = render(packing, size=(200, 100), view=(0, 0), clip=([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
                     occlusion=False, up="z")
    # Screen x is the y coordinate: the second sphere is on the right half.
    assert covered(whole[:, 100:]).sum() > 1000 and covered(whole[:, :100]).sum() > 1000
    assert covered(clipped[:, 100:]).sum() == 0
    np.testing.assert_array_equal(clipped[:, :100], whole[:, :100])  # the view stays put


def test_render_writes_a_png_of_the_asked_size(tmp_path):
    rng = np.random.default_rng(1)
    grid = np.stack(np.meshgrid(*[np.arange(4.0)] * 3), axis=-1).reshape(-1, 3)
    packing = spheres(grid, rng.uniform(0.1, 0.5, len(grid)))
    image = render(packing, tmp_path / "cube.png", size=(160, 90))
    assert image.shape == (90, 160, 3)
    written = matplotlib.image.imread(tmp_path / "cube.png")
    assert written.shape[:2] == (90, 160)
    np.testing.assert_allclose(written[:, :, :3] * 255, image, atol=1)
    assert covered(image).mean() > 0.2
    assert picture(packing, tmp_path / "p.png", size=(64, 48)).path.exists()


def test_render_of_a_2d_packing_draws_circles():
    image = render(spheres([[0.0, 0.0], [1.0, 0.0]], [0.5, 0.5]), size=(300, 200))
    assert image.shape == (200, 300, 3)
    assert covered(image).mean() > 0.05


# ---------------------------------------------------------------------------------------------- slices
def four_d_packing():
    """Spheres whose cuts by the flat x3 = 0 and the plane x2 = x3 = 0 are known."""
    centers = [[0, 0, 0, 0.0], [2, 0, 0, 0.3], [0, 2, 0.4, 0.0], [2, 2, 0, 0.9], [4, 0, 0.3, 0.4]]
    return spheres(centers, [1.0, 0.5, 0.6, 0.5, 0.6])


def test_3d_slice_of_a_4d_packing():
    packing = four_d_packing()
    centers, radii, index = slice_balls(packing.centers, packing.radii, (0, 1, 2), at=np.zeros(4))
    np.testing.assert_array_equal(index, [0, 1, 2, 4])  # the fourth is 0.9 away, radius 0.5
    np.testing.assert_allclose(radii, np.sqrt([1.0, 0.25 - 0.09, 0.36, 0.36 - 0.16]))
    np.testing.assert_array_equal(centers[2], [0, 2, 0.4])
    image = render(packing, at=np.zeros(4), size=(200, 120))
    assert covered(image).mean() > 0.1
    # A slice that misses every sphere is a blank picture.
    blank = render(packing, at=[0, 0, 0, 5.0], size=(40, 30))
    assert covered(blank).sum() == 0


def test_2d_slice_of_a_loaded_4d_packing_without_shape(tmp_path):
    packing = nd.Packing.load(four_d_packing().save(tmp_path / "four.npz"))
    assert packing.shape is None
    ax = plot(packing, at=np.zeros(4))
    assert len(ax.collections) == 1  # the circles; no outline without a shape
    assert len(ax.collections[0].get_paths()) == 4  # x2 = x3 = 0 misses only the fourth (0.9 away)
    picture(packing, tmp_path / "slice.svg", at=np.zeros(4))
    assert (tmp_path / "slice.svg").read_text().count("<svg") == 1


def test_4d_packing_from_pack_slices_with_outline(tmp_path):
    packing = nd.pack(nd.Box(np.zeros(4), np.ones(4)), n=12, seed=0)
    path = picture(packing, tmp_path / "slice.png", kind="slice", at=np.full(4, 0.5)).path
    assert path.stat().st_size > 5000


# ---------------------------------------------------------------------------------------------- 2-D files
def test_2d_pictures_are_written_as_svg_png_and_pdf(tmp_path):
    packing = nd.pack(nd.Box([0, 0], [2, 1]), n=40, seed=0)
    for suffix in (".svg", ".png", ".pdf"):
        path = picture(packing, tmp_path / f"square{suffix}").path
        assert path.stat().st_size > 1000
    vector = (tmp_path / "square.svg").read_text()
    assert vector.count("<path") > 40  # 40 circles stay vector (the colour bar is an image)
    save_figure(packing, tmp_path / "raster.svg", rasterized=True)
    raster = (tmp_path / "raster.svg").read_text()
    assert raster.count("<image") == vector.count("<image") + 1  # the circles as one embedded image ...
    assert 2 <= raster.count("<path") < vector.count("<path") - 35  # ... the outline and axes still vector


def test_many_circles_are_rasterized_in_svg(tmp_path):
    side = 80
    grid = (np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2) + 0.5) / side
    packing = spheres(grid, np.full(len(grid), 0.4 / side))
    save_figure(packing, tmp_path / "many.svg")
    text = (tmp_path / "many.svg").read_text()
    assert "<image" in text and text.count("<path") < 200  # 6,400 circles as vector paths would be 6,400 paths
    assert (tmp_path / "many.svg").stat().st_size < 2_500_000


# ---------------------------------------------------------------------------------------------- fill plot
def test_fill_plot_has_a_point_a_round(tmp_path):
    packing = nd.pack(nd.Box([0, 0], [1, 1]), n=25, seed=0)
    rounds = len(packing.stats.count)
    assert rounds > 1
    ax = plot_fill(packing)
    line = ax.lines[0]
    np.testing.assert_array_equal(line.get_xdata(), packing.stats.count)
    np.testing.assert_allclose(line.get_ydata(), packing.stats.fill)
    assert ax.get_xscale() == "log"
    ax = plot_fill([packing, packing], uncovered=True, labels=["a", "b"])
    assert len(ax.lines) == 2 and len(ax.lines[1].get_xdata()) == rounds
    np.testing.assert_allclose(ax.lines[0].get_ydata(), 1 - packing.stats.fill)
    assert ax.get_yscale() == "log"
    assert save_fill_figure(packing, tmp_path / "fill.png").stat().st_size > 5000
    assert picture(packing, tmp_path / "fill.svg", kind="fill").path.exists()


def test_fill_plot_needs_statistics(tmp_path):
    packing = nd.Packing.load(nd.pack(nd.Box([0, 0], [1, 1]), n=5, seed=0).save(tmp_path / "p.csv"))
    with pytest.raises(nd.NdpackError, match="statistics"):
        plot_fill(packing)


# ---------------------------------------------------------------------------------------------- mistakes
def test_bad_suffix_kind_and_dimension_are_explained(tmp_path):
    packing = spheres([[0.0, 0.0, 0.0]], [1.0])
    with pytest.raises(nd.ParameterError, match=r"\.png, \.svg, \.pdf"):
        picture(packing, tmp_path / "p.jpg")
    with pytest.raises(nd.ParameterError, match=r"\.png"):
        render(packing, tmp_path / "p.svg", size=(10, 10))
    with pytest.raises(nd.ParameterError, match="kind='slice'"):
        picture(packing, tmp_path / "p.svg", kind="render")
    with pytest.raises(nd.ParameterError, match="kind"):
        picture(packing, tmp_path / "p.png", kind="movie")
    with pytest.raises(nd.ParameterError, match=r"\.png, \.svg, \.pdf"):
        save_figure(packing, tmp_path / "p.gif")
    with pytest.raises(nd.DimensionError, match="2 or more"):
        picture(spheres([[0.0]], [1.0]), tmp_path / "p.png")
    with pytest.raises(nd.DimensionError, match="three different axes"):
        render(four_d_packing(), axes=(0, 1, 1))
    with pytest.raises(nd.ParameterError, match="clip"):
        render(packing, clip=([0, 0], [1, 0]))


def test_importing_pictures_stays_light():
    code = (
        "import sys, ndpack.pictures, ndpack.pictures.raycast, ndpack.pictures.plots; "
        "print(','.join(m for m in ('numba', 'matplotlib') if m in sys.modules))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == ""


# ---------------------------------------------------------------------------------------------- which way is up
def column(axis, count=5):
    """Touching unit-diameter spheres in a row along ``axis``: a tall box 5x longer than wide."""
    centers = np.zeros((count, 3))
    centers[:, axis] = np.arange(count)
    return spheres(centers, np.full(count, 0.5))


def covered_box(image):
    """(height, width) in pixels of what the spheres cover."""
    rows, columns = np.nonzero(covered(image))
    return rows.max() - rows.min() + 1, columns.max() - columns.min() + 1


def test_auto_up_stands_the_longest_extent_up():
    for axis, name in ((1, "y"), (2, "z"), (0, "x")):
        chosen = choose_up(column(axis))
        assert (chosen.axis, chosen.sign, chosen.name) == (axis, 1, name)
        assert "longest extent" in chosen.reason
        height, width = covered_box(render(column(axis), size=(120, 120), view=(35, 0), occlusion=False))
        assert height > 3 * width  # standing, not lying
    # Four spheres side by side lie flat on them (a base under the whole footprint, the lowest of two).
    block = spheres([[0, 0, 0], [1.0, 0, 0], [0, 0.6, 0], [1.0, 0.6, 0]], [0.4] * 4)
    assert choose_up(block).name == "z" and "stands on its base" in choose_up(block).reason
    # No base and nothing clearly longest (one ball): z, as always.
    assert "default" in choose_up(spheres([[0.0, 0, 0]], [1.0])).reason
    # Beyond three dimensions the third axis of the slice stands up; given axes, the last.
    assert choose_up(four_d_packing()).name == "z"
    assert choose_up(column(2), axes=(2, 0, 1)).name == "y"


def test_up_can_be_asked_for_and_turns_the_picture():
    tall = column(1)
    assert choose_up(tall, "z").name == "z" and choose_up(tall, "z").reason == "asked for"
    assert (choose_up(tall, "-y").axis, choose_up(tall, "-y").sign) == (1, -1)
    height, width = covered_box(render(tall, size=(120, 120), view=(0, 0), occlusion=False, up="z"))
    assert width > 3 * height  # laid down along screen x
    # Upside down: the red sphere on top (+z) goes to the bottom.
    red, blue = [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]
    pair = spheres([[0, 0, 1.0], [0, 0, -1.0]], [0.5, 0.5])
    for up, red_on_top in (("z", True), ("-z", False)):
        image = cast_spheres_of(pair, [red, blue], up)
        top, bottom = image[30, 50].astype(int), image[90, 50].astype(int)
        assert (top[0] > top[2]) == red_on_top and (bottom[0] > bottom[2]) != red_on_top
    with pytest.raises(nd.ParameterError, match=r"auto, x, y, z, -x, -y, -z"):
        render(tall, up="sideways")
    with pytest.raises(nd.ParameterError, match="not one of the axes drawn"):
        render(four_d_packing(), axes=(0, 1, 3), up="z")


def cast_spheres_of(packing, colours, up):
    """A render coloured ``colours`` (one per sphere) instead of by radius."""
    import ndpack.pictures.raycast as raycast

    original = raycast.radius_colours
    raycast.radius_colours = lambda radii, cmap: np.asarray(colours, dtype=np.float64)
    try:
        return render(packing, size=(100, 120), view=(0, 0), occlusion=False, outline=False, up=up)
    finally:
        raycast.radius_colours = original


def test_mesh_file_convention_decides_before_the_extent():
    tower = column(2)  # clearly longest along z ...
    for source, name in (("/data/tower.obj", "y"), ("scan.GLB", "y"), ("part.gltf", "y"), ("bracket.stl", "z"),
                         ("print.3mf", "z")):
        tower.params["source"] = source
        chosen = choose_up(tower)
        assert chosen.name == name and "by convention" in chosen.reason
    tower.params["source"] = "scan.ply"  # ... no convention: the extent decides
    assert choose_up(tower).name == "z" and "longest" in choose_up(tower).reason
    tower.params["source"] = "box:dim=3"  # a built-in shape: no file
    assert choose_up(tower).name == "z" and "longest" in choose_up(tower).reason
    # A packing made in Python keeps the file's name on its TriangleMesh shape (PLY: no convention;
    # this cow is y-up, 1.6x longer along x than y: the default, z).
    packing = spheres([[0.0, 0.0, 0.0]], [0.1])
    packing.shape = nd.TriangleMesh.load(MESH)
    assert choose_up(packing).name == "z"
    packing.shape.name = "cow.obj"
    assert choose_up(packing).name == "y"


def test_the_png_records_which_way_is_up(tmp_path):
    from PIL import Image

    render(column(1), tmp_path / "tall.png", size=(40, 40))
    description = Image.open(tmp_path / "tall.png").info["Description"]
    assert description.startswith("ndpack render: up y (the longest extent")


def test_render_command_takes_up_and_says_which(tmp_path, capsys):
    from ndpack.cli import main

    path = column(1).save(tmp_path / "tall.npz")
    image = tmp_path / "tall.png"
    assert main(["render", str(path), "-o", str(image), "--size", "60x60"]) == 0
    assert "up:    y (the longest extent, 5.0x the next)" in capsys.readouterr().out
    for up in ("z", "-y"):
        assert main(["render", str(path), "-o", str(image), "--size", "60x60", f"--up={up}"]) == 0
        assert f"up:    {up} (asked for)" in capsys.readouterr().out
    assert main(["render", str(path), "-o", str(tmp_path / "slice.svg"), "--up", "x"]) == 0
    assert "up:    x (asked for)" in capsys.readouterr().out
    assert main(["render", str(path), "-o", str(image), "--size", "60x60", "--up", "-y"]) == 0  # no `=` needed
    assert "up:    -y (asked for)" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["render", str(path), "--up", "w"])
    error = capsys.readouterr().err
    assert "--up" in error and "'auto', 'x', 'y', 'z', '-x', '-y', '-z'" in error


def test_render_help_says_how_to_turn_the_view(capsys):
    from ndpack.cli import main

    with pytest.raises(SystemExit):
        main(["render", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--up {auto,x,y,z,-x,-y,-z}" in text and "--view AZIMUTH,ELEVATION" in text and "--axes" in text
    assert "broadest base" in text and ".obj/.gltf/.glb y" in text
