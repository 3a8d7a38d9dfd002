"""x3p round trips read back with x3pio, PNG pictures checked by their header, unit choice."""

import struct

import numpy as np
import pytest
import x3pio

from machinesim.exceptions import InputError
from machinesim.metrology import export
from machinesim.metrology.export import export_x3p, length_unit, plot_height_map, plot_profile

MM = 1e-3
UM = 1e-6
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def rough_map():
    rng = np.random.default_rng(0)
    x = np.linspace(1 * MM, 2 * MM, 101)
    y = np.linspace(-0.5 * MM, 0.3 * MM, 81)
    grid_x, grid_y = np.meshgrid(x, y)
    z = 1e-7 * np.sin(grid_x / (0.1 * MM)) + rng.normal(0.0, 2e-9, grid_x.shape) - 2 * MM
    z[3, 4] = np.nan
    return x, y, z


def png_size(path):
    """Width and height from a PNG file's IHDR chunk, after checking the signature."""
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def test_x3p_round_trip_keeps_heights_bit_for_bit(tmp_path):
    x, y, z = rough_map()
    path = tmp_path / "map.x3p"
    export_x3p(path, x, y, z, comment="machinesim test")
    stored = x3pio.read(path)
    layer = stored.layers[0]
    # float64 'D' storage: the heights come back exactly, NaN where no surface.
    assert stored.header.z.data_type == x3pio.DataType.FLOAT64
    np.testing.assert_array_equal(layer.z, z)
    points = layer.points()
    grid_x, grid_y = np.meshgrid(x, y)
    # The grid is stored as offset + index * increment: linspace axes agree with that to
    # their own round-off (~1e-19 m at 2 mm); 1e-15 m fails on a wrong offset or increment.
    np.testing.assert_allclose(points[..., 0], grid_x, rtol=0, atol=1e-15)
    np.testing.assert_allclose(points[..., 1], grid_y, rtol=0, atol=1e-15)
    assert stored.metadata.comment == "machinesim test"
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left behind


def test_x3p_refuses_an_irregular_grid_and_leaves_the_old_file(tmp_path):
    x, y, z = rough_map()
    path = tmp_path / "map.x3p"
    export_x3p(path, x, y, z)
    before = path.read_bytes()
    bent = x.copy()
    bent[50] += 0.1 * UM
    with pytest.raises(InputError, match="regular grid along x"):
        export_x3p(path, bent, y, z)
    with pytest.raises(InputError, match="z \\(ny, nx\\)"):
        export_x3p(path, x, y, z.T)
    assert path.read_bytes() == before
    assert list(tmp_path.iterdir()) == [path]


def test_plot_profile_writes_a_png(tmp_path):
    s = np.arange(2000) * 0.5 * UM
    z = -np.clip(2 * UM - np.abs(s - 0.5 * MM), 0.0, None)
    z[100:120] = np.nan
    path = tmp_path / "profile.png"
    plot_profile(path, s, z, title="groove")
    assert png_size(path) == (1600, 1000)
    # A line plot at 200 dpi: tens of kB; far more would mean an image, far less an empty one.
    assert 10_000 < path.stat().st_size < 1_000_000
    assert list(tmp_path.iterdir()) == [path]


def test_plot_height_map_writes_a_png_on_regular_and_irregular_grids(tmp_path):
    x, y, z = rough_map()
    regular = tmp_path / "map.png"
    plot_height_map(regular, x, y, z, title="map")
    assert png_size(regular) == (1600, 1000)
    assert 10_000 < regular.stat().st_size < 2_000_000
    irregular = tmp_path / "irregular.png"
    plot_height_map(irregular, x**1.5 / np.sqrt(2 * MM), y, z)
    assert png_size(irregular) == (1600, 1000)
    assert 10_000 < irregular.stat().st_size < 2_000_000
    with pytest.raises(InputError, match="only NaN"):
        plot_height_map(tmp_path / "empty.png", x, y, np.full_like(z, np.nan))
    assert not (tmp_path / "empty.png").exists()


def test_each_writer_refuses_a_path_not_ending_in_its_format(tmp_path):
    # export_x3p(tmp_path / "map.png", ...) wrote x3p bytes under a picture's name without a
    # word (and plot_profile PNG bytes under .x3p, to_toml TOML under .json ...), as
    # Part.export_ply did under .stl; the ending may be in any case, and nothing is written
    from machinesim.budget import Budget, BudgetRow
    from machinesim.errors import ErrorModel

    x, y, z = rough_map()
    s, profile = x, z[0]
    budget = Budget((BudgetRow("s", "x", "um", 0.5, 0.3, 0.64),))
    writers = {"x3p": ("export_x3p", "an ISO 25178-72 x3p height map",
                       lambda path: export_x3p(path, x, y, z)),
               "png": ("plot_profile", "a PNG picture",
                       lambda path: plot_profile(path, s, profile)),
               "PNG": ("plot_height_map", "a PNG picture",
                       lambda path: plot_height_map(path, x, y, z)),
               "Png": ("Budget.plot", "a PNG picture", budget.plot),
               "toml": ("ErrorModel.to_toml", "a TOML error model", ErrorModel().to_toml)}
    for ending, (writer, what, write) in writers.items():
        for wrong, found in (("map.stl", "ends in .stl"), ("map", "has no ending"),
                             (f"map.{ending}.tmp", "ends in .tmp")):
            path = tmp_path / wrong
            with pytest.raises(InputError, match=rf"{writer} writes {what}, and the path "
                                                 rf"{found}: expected a name ending in "
                                                 rf"\.{ending.lower()}") as info:
                write(path)
            assert info.value.key == "path" and info.value.source == str(path)
        assert list(tmp_path.iterdir()) == []
        write(tmp_path / f"map.{ending}")  # its own ending, in any case, is written
        assert (tmp_path / f"map.{ending}").stat().st_size > 0
        (tmp_path / f"map.{ending}").unlink()


def test_each_writer_refuses_what_is_no_file_name(tmp_path):
    # a file object, bytes or None given as the path passed check_ending ("the writing says
    # so") and reached Path(path): a TypeError traceback, 'expected str, bytes or
    # os.PathLike object, not BytesIO', where every other bad input is an InputError
    import io

    from machinesim._io import write_atomic
    from machinesim.errors import ErrorModel

    x, y, z = rough_map()
    writers = {"export_x3p": lambda path: export_x3p(path, x, y, z),
               "plot_profile": lambda path: plot_profile(path, x, z[0]),
               "ErrorModel.to_toml": ErrorModel().to_toml}
    for writer, write in writers.items():
        for path, kind in ((io.BytesIO(), "BytesIO"), (io.StringIO(), "StringIO"),
                           (b"map.png", "bytes"), (None, "NoneType")):
            with pytest.raises(InputError, match=rf"{writer} writes .* to a file name ending "
                                                 rf"in \.\w+: expected a file name \(str or "
                                                 rf"pathlib\.Path\), got {kind}$") as info:
                write(path)
            assert info.value.key == "path"
    with pytest.raises(InputError, match=r"expected a file name \(str or pathlib\.Path\), got "
                                         r"BytesIO"):
        write_atomic(io.BytesIO(), b"x")  # every writer's sink (Part.export_ply's too)
    assert list(tmp_path.iterdir()) == []


def test_length_unit_follows_the_data_range():
    assert length_unit([0.0, 2 * MM]) == ("mm", 1e-3)
    assert length_unit([-2 * MM, -2 * MM + 3 * UM]) == ("um", 1e-6)
    assert length_unit([0.0, 50e-9, np.nan]) == ("nm", 1e-9)
    assert length_unit([0.2e-9, 0.3e-9]) == ("nm", 1e-9)  # below 1 nm still reads in nm
    assert length_unit([5 * UM, 5 * UM]) == ("um", 1e-6)  # constant: sized by magnitude


def test_axis_far_from_zero_is_drawn_from_a_named_offset():
    # 200 nm of form on a face 2 mm below zero: nm from z + 2 mm, not -2000000 nm.
    heights = -2 * MM + np.array([-100e-9, 0.0, 100e-9])
    offset, factor, label = export._axis(heights, "z")
    assert (offset, factor, label) == (-2 * MM, 1e-9, "z + 2 mm (nm)")
    offset, factor, label = export._axis(np.array([10.0, 10.1]) * MM, "x")
    assert (offset, factor) == (10.05 * MM, 1e-6)
    assert label == "x \N{MINUS SIGN} 10.05 mm (\N{MICRO SIGN}m)"
    assert export._axis(np.array([1.0, 2.0]) * MM, "x") == (0.0, 1e-3, "x (mm)")
