"""Generate, bake and build a region as short steps, for File › Import › Voxel World
and the Bake operators (one code path, run at once or from a modal timer).

    job = Job(world, region, per=..., light=..., ...)
    for stage, frac in job.steps(): ...   # or job.run() -> objects
    job.cancel()                           # removes everything the job made

Nothing shows in the scene until the last step links the finished collection, and
cancel() removes every datablock the job created (objects, meshes, materials,
images, node groups, collections), so an interrupted job leaves the scene as it was.
Chunks it generated stay in the world file (they are the world, not the scene).
"""
from __future__ import annotations

import time

import bpy

KINDS = ("objects", "meshes", "materials", "images", "node_groups", "collections")
# names of what bake builds (blender/bake.py): cancel removes only new datablocks
# named so, never something the user made while a modal job ran
OURS = ("voxel_", "voxels_", "Voxel ", "chunk_", "tile_", "plant_", "plants_", "glTF Material Output")
ROWS = 4  # chunk rows generated per step


def region_of_mode(world, mode: str, region=(0, 0, 0, 0), size: int = 64):
    """(x0, y0, x1, y1) of a region mode: "region" as given, "origin" a size×size
    square around (0, 0), "generated" the chunks the world file already holds."""
    from ..core.errors import VoxelError
    if mode == "region":
        return tuple(int(v) for v in region)
    if mode == "origin":
        h = max(1, int(size)) // 2
        return (-h, -h, -h + max(1, int(size)), -h + max(1, int(size)))
    if mode == "generated":
        keys = list(world.file.chunk_keys())
        if not keys:
            raise VoxelError("the world has no generated chunks yet (pick a region)")
        xs, ys = [k[0] for k in keys], [k[1] for k in keys]
        return (16 * min(xs), 16 * min(ys), 16 * (max(xs) + 1), 16 * (max(ys) + 1))
    raise VoxelError(f"unknown region mode {mode!r}")


class Job:
    def __init__(self, world, region, *, per="region", method="greedy", instances=False,
                 light="atlas", style="blender", hours=12.0, tile=64, name=None,
                 generate=True, build=True):
        from .. import bake
        self.world = world
        self.region = bake.check_region(*region)
        self.kw = dict(per=per, method=method, instances=instances, light=light, tile=tile)
        self.style, self.hours, self.generate, self.build = style, hours, generate, build
        self.generated = 0
        self.name = name or "Voxel Bake {} {} {} {}".format(*self.region)
        self.objects: list = []
        self.bake = None
        self.collection = None
        self._before = None

    def _snapshot(self):
        return {k: set(getattr(bpy.data, k)) for k in KINDS}

    def steps(self):
        """Generator of (stage, fraction in 0..1); returns the objects."""
        from .. import bake
        from . import bake as BB
        self._before = self._snapshot()
        x0, y0, x1, y1 = self.region
        if self.generate and not getattr(self.world, "readonly", False):
            rows = list(range(y0 >> 4, ((y1 - 1) >> 4) + 1))
            for i in range(0, len(rows), ROWS):
                yield "generate", i / len(rows)
                keys = [(cx, cy) for cy in rows[i:i + ROWS]
                        for cx in range(x0 >> 4, ((x1 - 1) >> 4) + 1)]
                self.generated += self.world.generate_area(keys)
        if not self.build:  # generating only (the chunks go to the world file)
            yield "done", 1.0
            return self.objects
        yield "read", 0.0
        blocks = bake.region_of(self.world, x0, y0, x1, y1)
        extra, note = bake.inputs(self.world, x0, y0, x1, y1, blocks)  # colours, Minecraft models
        self.bake = yield from bake.steps(blocks, origin=(x0, y0, 0), **extra, **self.kw)
        self.bake.note = note
        del blocks
        self.collection = bpy.data.collections.new(self.name)
        self.objects = yield from BB.build_steps(self.bake, style=self.style,
                                                 collection=self.collection, hours=self.hours)
        bpy.context.scene.collection.children.link(self.collection)  # only when whole
        yield "done", 1.0
        return self.objects

    def run(self, progress=None) -> list:
        for stage, frac in self.steps():
            if progress:
                progress(stage, frac)
        return self.objects

    def cancel(self) -> None:
        """Remove every datablock made since steps() started."""
        if self._before is None:
            return
        if self.collection is not None:
            for parent in [bpy.context.scene.collection, *bpy.data.collections]:
                if self.collection.name in parent.children:
                    parent.children.unlink(self.collection)
        for kind in ("objects", "collections", "meshes", "materials", "node_groups", "images"):
            data = getattr(bpy.data, kind)
            for idb in [d for d in data if d not in self._before[kind]
                        and d.name.startswith(OURS)]:
                data.remove(idb)
        self.objects, self.collection, self._before = [], None, None


class Runner:
    """Drives a Job from a modal operator: step() runs steps for about `budget`
    seconds and says whether the job is done; progress goes to the window manager's
    progress cursor and the status bar."""

    def __init__(self, job: Job, context=None, budget: float = 0.05):
        self.job, self.budget = job, budget
        self.gen = job.steps()
        self.stage, self.frac, self.done = "start", 0.0, False
        self.context = context

    def step(self) -> bool:
        t0 = time.perf_counter()
        while not self.done:  # at least one step per call
            try:
                self.stage, self.frac = next(self.gen)
            except StopIteration:
                self.done = True
            if time.perf_counter() - t0 >= self.budget:
                break
        self._show()
        return self.done

    def text(self) -> str:
        return f"Voxel: {self.stage} {100 * self.frac:.0f}%  (Esc cancels)"

    def _show(self):
        ctx = self.context
        if ctx is None or ctx.window_manager is None:
            return
        ctx.window_manager.progress_update(int(100 * self.frac))
        ws = getattr(ctx, "workspace", None)
        if ws is not None:
            ws.status_text_set(None if self.done else self.text())

    def cancel(self):
        self.gen.close()
        self.job.cancel()
        self.done = True
        self._show()


class ModalJob:
    """Operator mixin: make_job(context) -> Job, finish(context, job). execute() runs
    the job at once (scripts, background); start() runs it modally: timer steps, the
    progress in the status bar, Esc cancels and removes what was made."""

    _runner = None
    _timer = None

    def make_job(self, context) -> Job:
        raise NotImplementedError

    def finish(self, context, job) -> set | None:
        """The job is done: say so (a result set overrides FINISHED: a failed export)."""
        self.report({"INFO"}, f"{len(job.objects)} objects, {job.bake.triangles} triangles")

    def failed(self, context) -> None:
        """After a failure (the job cancelled): undo what make_job made (a new world file)."""

    def kept(self) -> str:
        """What stays in the world file after a failure, said after it."""
        return ""

    def _failed(self, context, e) -> bool:
        from . import session
        try:
            self.failed(context)
        finally:
            told = session.refused(self, e, kept=self.kept())
        return told

    def execute(self, context):
        job = None
        try:
            job = self.make_job(context)
            job.run()
        except Exception as e:  # noqa: BLE001 - a full disk is one line (session.refused)
            if job is not None:
                job.cancel()
            if not self._failed(context, e):
                raise
            return {"CANCELLED"}
        return self.finish(context, job) or {"FINISHED"}

    def start(self, context):
        try:
            job = self.make_job(context)
        except Exception as e:  # noqa: BLE001
            if not self._failed(context, e):
                raise
            return {"CANCELLED"}
        wm = context.window_manager
        self._runner = Runner(job, context)
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._runner.cancel()
            self._end(context)
            self.report({"WARNING"}, "cancelled: nothing was added to the scene")
            return {"CANCELLED"}
        if event.type != "TIMER":  # (any timer: a step is short either way)
            return {"PASS_THROUGH"}
        try:
            done = self._runner.step()
        except Exception as e:  # noqa: BLE001 - whatever stops the job, clean up first
            self._runner.cancel()
            self._end(context)
            if not self._failed(context, e):  # a bug: its traceback, and still one line
                import traceback
                traceback.print_exc()
                self.report({"ERROR"}, f"{type(e).__name__}: {e}")
            return {"CANCELLED"}
        if not done:
            return {"RUNNING_MODAL"}
        self._end(context)
        return self.finish(context, self._runner.job) or {"FINISHED"}

    def _end(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if getattr(context, "workspace", None) is not None:
            context.workspace.status_text_set(None)


class FileJob(ModalJob):
    """A ModalJob behind a file browser (mix in before bpy.types.Operator and
    ImportHelper): OK in the browser runs it modally; scripts and background run
    it at once."""

    modal_run: bpy.props.BoolProperty(default=False, options={"HIDDEN", "SKIP_SAVE"})

    def invoke(self, context, event):
        from bpy_extras.io_utils import ImportHelper
        self.modal_run = True
        return ImportHelper.invoke(self, context, event)

    def execute(self, context):
        if self.modal_run and context.window is not None:
            return self.start(context)
        return ModalJob.execute(self, context)
