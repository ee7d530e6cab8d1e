"""Every switch and knob of the pipeline; defaults follow the thesis's §6.2 setup."""
from __future__ import annotations

from dataclasses import dataclass, fields, replace

from ..core.errors import VoxelError

DEBUG_VIEWS = ("none", "albedo", "normal", "depth", "light", "aggregation", "culling")
# effect name -> (field, value when switched on by --effects)
EFFECTS = ("shadows", "ssao", "fog", "dof", "godrays", "waving", "smooth_mag",
           "fill_holes", "msaa_alpha", "per_sample", "tonemap", "clouds", "cloud_shadows",
           "water", "ssr", "sea", "fade", "stars", "walls")

TRANSPARENCY = ("peel", "oit")


@dataclass
class Settings:
    distance: int = 8             # view distance in chunks
    far: int = 0                  # far terrain out to this many chunks (0: off; render/far.py)
    far_draft: bool = False       # far tiles at half their resolution (the view's draft frames)
    plants_reach: float = 0.0     # double-sided plants (grass, flowers) drawn out to this
                                  # many blocks from the eye; 0: everywhere (the view's
                                  # draft frames: a third of the G-buffer's cost there)
    light_radius: int = 8         # chunks around the centre with exact light (bounded volume)
    msaa: int = 2                 # 1, 2, 4, 8 (clamped to the context's maximum)
    per_sample: bool = True       # MSAA shading per sample (else per pixel)
    msaa_alpha: bool = True       # alpha test per sample for plants and leaves
    shadows: bool = True
    shadow_size: int = 2048
    shadow_fade: float = 50.0     # blocks from the camera: shadows fade linearly to none
                                  # there (§5.4.1, "ve vzdálenosti 50 bloků")
    peel_layers: int = 3          # transparency layers, 0..3
    transparency: str = "peel"    # "peel" (depth peeling, peel_layers) or "oit" (weighted
                                  # blended OIT, one pass: render/oit.py, README)
    ssao: bool = False            # off by default, as in the thesis
    ssao_radius: float = 1.0      # blocks
    fog: bool = True              # atmosphere
    dof: bool = True              # distance blur
    godrays: bool = True
    godray_strength: float = 1.0
    waving: bool = True
    smooth_mag: bool = True       # edge-aware texture magnification
    anisotropy: float = 4.0       # GL anisotropic filtering (the thesis used it); 1 on
                                  # software rasterizers, see Renderer.max_anisotropy
    fill_holes: bool = True       # T-junction hiding
    debug: str = "none"
    fov: float = 70.0
    time: float = 0.0             # seconds, drives waving
    # the look (issue 20): light/atmosphere.py, render/sky.py, shaders/include/*.glsl
    tonemap: bool = True          # AgX-like tone curve (else sRGB, clipped)
    exposure: float = 0.0         # EV on top of the hour's own exposure (light.daytime)
    haze: float = 1.0             # density of the haze (the fog effect) at sea level, x
    fog_height: float = 40.0      # blocks over which the haze thins by 1/e upwards
    clouds: bool = True
    cloud_cover: float = 0.45     # 0 clear .. 1 overcast
    cloud_height: float = 240.0   # z of the cloud layer
    cloud_speed: float = 12.0     # blocks the clouds drift per minute of the day
    cloud_shadows: bool = True
    water: bool = True            # water and glass: sky reflections, Fresnel, sun glint,
                                  # waves, colour by depth
    ssr: bool = True              # water reflects the scene on screen (screen-space reflection)
    sea: bool = True              # a sea to the horizon beyond the shown area
    sea_level: int = -1           # the world's water level (its generator's, water up to
                                  # this z; source.sea_level); -1: no sea
    sea_from: float = 0.0         # blocks from the camera (horizontally) from which the sea
                                  # covers what lies below it outside the shown area (far
                                  # terrain: its ring's edge)
    fade: bool = True             # the shown area's edge fades into the sky (horizon)
    fade_distance: float = 0.0    # blocks where the fade ends; 0: the view distance's edge
    fade_width: float = 0.3       # the fade's width, a fraction of its distance
    stars: bool = True
    walls: bool = True            # the shown area's outer wall closed where its meshes are
                                  # open (streamed chunks: render/walls.py)

    def with_effects(self, spec: str | None) -> "Settings":
        """Apply '--effects' text: 'all', 'none', or comma-separated [+-]name items."""
        if not spec:
            return self
        s = replace(self)
        for item in (t.strip() for t in spec.split(",") if t.strip()):
            if item in ("all", "none"):
                for e in EFFECTS:
                    setattr(s, e, item == "all")
                s.peel_layers = 3 if item == "all" else 0
                if item == "none":
                    s.transparency = "peel"
                continue
            on = not item.startswith("-")
            name = item.lstrip("+-")
            if name.startswith("peel") and name[4:].isdigit():
                s.peel_layers = int(name[4:])
                s.transparency = "peel"
            elif name == "oit":
                s.transparency = "oit" if on else "peel"
            elif name.startswith("msaa") and name[4:].isdigit():
                s.msaa = int(name[4:])
            elif name in EFFECTS:
                setattr(s, name, on)
            else:
                raise VoxelError(f"unknown effect {name!r} (known: {', '.join(EFFECTS)}, "
                                 "peel0..peel3, oit, msaa1/2/4/8, all, none)")
        s.check()
        return s

    def with_values(self, items) -> "Settings":
        """Apply '--set NAME=VALUE' items (any field; numbers, on/off for switches)."""
        s = replace(self)
        kinds = {f.name: f.type for f in fields(Settings)}
        for item in items or ():
            name, eq, text = item.partition("=")
            name, text = name.strip(), text.strip()
            if not eq or name not in kinds:
                raise VoxelError(f"--set wants NAME=VALUE with NAME one of {', '.join(kinds)}"
                                 if eq else f"--set {item!r}: expected NAME=VALUE")
            kind = kinds[name]
            try:
                if kind == "bool":
                    if text.lower() not in ("1", "0", "on", "off", "true", "false", "yes", "no"):
                        raise ValueError
                    value = text.lower() in ("1", "on", "true", "yes")
                else:
                    value = {"int": int, "float": float, "str": str}[kind](text)
            except ValueError:
                raise VoxelError(f"--set {name}: {text!r} is not a valid {kind}") from None
            setattr(s, name, value)
        s.check()
        return s

    def check(self) -> None:
        if self.debug not in DEBUG_VIEWS:
            raise VoxelError(f"unknown debug view {self.debug!r} (known: {', '.join(DEBUG_VIEWS)})")
        if not 0 <= self.peel_layers <= 3:
            raise VoxelError("peel layers must be 0..3")
        if self.transparency not in TRANSPARENCY:
            raise VoxelError(f"unknown transparency {self.transparency!r} "
                             f"(known: {', '.join(TRANSPARENCY)})")
        if self.msaa not in (1, 2, 4, 8):
            raise VoxelError("msaa must be 1, 2, 4 or 8")
        if not 1 <= self.distance <= 32:
            raise VoxelError("view distance must be 1..32 chunks")
        if not 0 <= self.far <= 256:
            raise VoxelError("far distance must be 0..256 chunks (0: off)")
        for name, lo, hi in (("light_radius", 1, 32), ("shadow_size", 256, 8192),
                             ("shadow_fade", 1.0, 1000.0), ("godray_strength", 0.0, 10.0),
                             ("anisotropy", 1.0, 16.0), ("fov", 10.0, 150.0),
                             ("ssao_radius", 0.1, 8.0), ("exposure", -10.0, 10.0),
                             ("haze", 0.0, 20.0), ("fog_height", 1.0, 1000.0),
                             ("cloud_cover", 0.0, 1.0), ("cloud_height", 0.0, 1000.0),
                             ("cloud_speed", 0.0, 1000.0), ("sea_level", -1, 255),
                             ("fade_distance", 0.0, 100000.0), ("fade_width", 0.01, 1.0),
                             ("sea_from", 0.0, 100000.0), ("plants_reach", 0.0, 100000.0)):
            if not lo <= getattr(self, name) <= hi:
                raise VoxelError(f"{name} must be between {lo} and {hi}")


def names() -> list[str]:
    return [f.name for f in fields(Settings)]
