import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.light import daytime


def test_table():
    noon, night = daytime.at(12), daytime.at(0)
    assert noon.u == pytest.approx(0.8) and night.u == 0.0
    assert noon.sun_height > 0.9 and night.sun_height < -0.9
    assert daytime.at(6).sun_dir[0] == pytest.approx(1.0)  # rises in +x
    assert daytime.at(18).sun_dir[0] == pytest.approx(-1.0)
    assert daytime.at(25.5) == daytime.at(1.5)  # wraps
    assert night.light_dir == night.moon_dir and noon.light_dir == noon.sun_dir
    a, b = daytime.at(11.999), daytime.at(12.001)  # continuous
    assert all(abs(x - y) < 1e-3 for x, y in zip(a.ambient + a.zenith, b.ambient + b.zenith))
    assert sum(noon.ambient) > 3 * sum(night.ambient)


def test_parse_time():
    assert daytime.parse_time("06:30") == 6.5
    assert daytime.parse_time("24:00") == 0.0
    assert daytime.parse_time("noon") == 12.0
    for bad in ("25:00", "12:60", "noon!", "", "7"):
        with pytest.raises(VoxelError):
            daytime.parse_time(bad)
