"""What the pipeline asks of a GPU, in one small interface with two implementations:
moderngl (`mgl.MglDevice`: the CLI, tests and bench, on a standalone EGL context) and
Blender's own `gpu` module (`blender/liveview/device.py`: the live view and renders in
Blender, on whatever backend Blender runs: OpenGL, Vulkan, Metal).

The interface is what both can do: textures without sampler state (every texture is
sampled nearest and clamped; shaders filter and repeat by hand), whole uploads plus
one layer of an array texture, framebuffers of textures, programs from shaders/ (their
interface from render/glsl.py), one uniform block per frame, per-draw values, vertex
buffers of packed quads drawn in ranges, and a few fixed-function states. What only
moderngl has (multisampled targets) is asked for through `max_samples`.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

# texture formats: name -> (components, bytes per component)
FORMATS = {"rgba8": (4, 1), "srgba8": (4, 1), "rgba16f": (4, 2), "rgba32f": (4, 4), "r8": (1, 1),
           "r16": (1, 2), "r16f": (1, 2), "r32f": (1, 4), "depth": (1, 4)}


@dataclass(frozen=True)
class State:
    """Fixed-function state of a pass."""
    depth: str | None = None   # None: no depth test; "less", "lequal" or "greater"
    write: bool = True         # depth writes (with a depth test)
    cull: bool = False         # back faces dropped (counter-clockwise fronts)
    blend: str | None = None   # None, or "add": ONE, ONE


@dataclass(eq=False)
class Texture:
    """A device texture: `obj` is the device's own; `size` (w, h), `layers` (0: not an
    array), `samples` (1: not multisampled)."""
    obj: object
    size: tuple
    fmt: str
    layers: int = 0
    samples: int = 1

    @property
    def nbytes(self) -> int:
        c, b = FORMATS[self.fmt]
        return self.size[0] * self.size[1] * max(1, self.layers) * self.samples * c * b


@dataclass(eq=False)
class Target:
    """A framebuffer of device textures (colours in location order, a depth or None)."""
    obj: object
    colors: tuple
    depth: Texture | None

    @property
    def size(self) -> tuple:
        return (self.colors[0] if self.colors else self.depth).size


class Device:
    """The interface (see the module docstring). Sizes are (w, h); image rows start at
    the bottom (GL's order) unless a method says otherwise."""
    kind = ""            # "moderngl", "gpu"
    backend = ""         # the graphics API underneath: "OPENGL", "VULKAN", "METAL"
    max_samples = 1      # multisampled targets up to this many samples (1: none)
    software = False     # a software rasterizer (llvmpipe): cost models differ

    # -- resources
    def texture(self, size, fmt: str, *, layers: int = 0, samples: int = 1,
                data: np.ndarray | None = None) -> Texture:
        """data: the whole texture, rows bottom first (uint8 for the 8-bit formats,
        uint16 for r16, float32 for the float ones)."""
        raise NotImplementedError

    def write_layer(self, tex: Texture, layer: int, data: np.ndarray) -> None:
        """Replace one layer of an array texture (the light volume's chunks)."""
        raise NotImplementedError

    def target(self, colors, depth: Texture | None = None) -> Target:
        raise NotImplementedError

    def program(self, vert: str, frag: str, defines: dict | None = None):
        """A program of shader files for these defines (compiled once, cached)."""
        raise NotImplementedError

    def mesh(self, words: np.ndarray):
        """A vertex buffer of quads: (4 n, 2) uint32, the packed vertex and its origin
        word (shaders/block.vert), drawn with the shared quad index pattern."""
        raise NotImplementedError

    def trimesh(self, words: np.ndarray, *indices: np.ndarray):
        """A vertex buffer of triangles (far terrain): words (n, k) uint32, the vertex
        input `in_f` (uvec<k>), and its index sets ((m,) uint32, three a triangle),
        each drawn on its own (`draw_tris`: e.g. a full and a coarse set)."""
        raise NotImplementedError

    def frame(self, data: bytes) -> None:
        """This frame's uniform block (render/frame.py packs it); every program that
        reads the block sees it from now on."""
        raise NotImplementedError

    def release(self, *objs) -> None:
        """Free textures, targets and meshes made here (None is ignored)."""
        raise NotImplementedError

    def close(self) -> None:
        """Free what the device made for itself (programs, the index pattern)."""

    # -- drawing
    @contextmanager
    def begin(self, target: Target | None, state: State = State(), clear: bool = False):
        """Draw into target (None: the framebuffer that is bound, e.g. the host's) with
        this state; clear: colours to 0 and, where the state writes depth, depth to 1."""
        raise NotImplementedError
        yield

    def state(self, state: State) -> None:
        """Change the state inside begin()."""
        raise NotImplementedError

    def use(self, prog, textures: dict, push: dict | None = None) -> None:
        """Bind a program, its textures (sampler name -> Texture) and values."""
        raise NotImplementedError

    def push(self, values: dict) -> None:
        """Per-draw values of the program in use."""
        raise NotImplementedError

    def draw(self, mesh=None, first: int = 0, quads: int = 0) -> None:
        """Quads [first, first + quads) of a mesh, or with no mesh one triangle that
        covers the target (fullscreen.vert)."""
        raise NotImplementedError

    def draw_tris(self, mesh, part: int = 0) -> None:
        """The triangles of one index set of a trimesh."""
        raise NotImplementedError

    # -- counting drawn samples, and skipping draws where none were (a device without
    # queries, as Blender's gpu module, returns None and always draws)
    def counter(self, key):
        """The samples-passed counter named key (made once, kept by the device), or None."""
        return None

    @contextmanager
    def counting(self, counter):
        """Count the samples that pass in the draws inside (counter None: nothing)."""
        yield

    @contextmanager
    def only_if(self, counter):
        """The draws inside run only where counting() last counted a sample: decided on
        the GPU, the CPU waits for nothing (None: they always run)."""
        yield

    def read(self, tex: Texture) -> np.ndarray:
        """A 2D texture's pixels (h, w, components), rows bottom first: uint8 for the
        8-bit formats, uint16 for r16, float32 otherwise."""
        raise NotImplementedError

    def finish(self) -> None:
        """Wait until the GPU has done what was drawn (bench timings)."""

