"""Settings text from the command line: --effects switches, --set tunes any field."""
import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.render import Settings


def test_set_parses_by_field_type():
    s = Settings().with_values(["godray_strength=2.5", "shadow_size=4096", "ssao=on",
                                "waving=0", "debug=depth", "fov = 55"])
    assert (s.godray_strength, s.shadow_size, s.ssao, s.waving, s.debug, s.fov) == \
        (2.5, 4096, True, False, "depth", 55.0)
    assert Settings().godray_strength == 1.0  # a copy: defaults untouched


@pytest.mark.parametrize("item", ["shadow_size=2.5", "fov=", "nope=1", "fov", "debug=sepia",
                                  "shadow_fade=-1", "ssao=2", "cloud_cover=1.5", "haze=-1",
                                  "exposure=20", "sea_level=300", "fade_width=0"])
def test_bad_set_is_a_user_error(item):
    with pytest.raises(VoxelError):
        Settings().with_values([item])


def test_effects_then_values():
    s = Settings().with_effects("none,+ssao,oit").with_values(["ssao_radius=2"])
    assert s.ssao and not s.shadows and s.transparency == "oit" and s.ssao_radius == 2.0


def test_the_look_has_switches():
    """Each effect of issue 20 is on by default (the renders use it) and switches off
    by --effects, like the thesis's effects."""
    look = ("tonemap", "clouds", "cloud_shadows", "water", "sea", "fade", "stars")
    s = Settings()
    assert all(getattr(s, e) for e in look)
    off = s.with_effects(",".join(f"-{e}" for e in look))
    assert not any(getattr(off, e) for e in look) and off.shadows
    assert not any(getattr(s.with_effects("none"), e) for e in look)
