"""``bpy.ops.wetcloth.bake()`` and ``bpy.ops.wetcloth.free_bake()``.

The bake simulates every Cloth object over the scene's frame range at its fps.  From the interface
it runs as a modal operator: frames for TICK s per timer tick (frame_loop.tick), progress in the
status bar, Esc cancels and keeps the frames baked so far.  From scripts and in background mode it runs to the end at once
(``cancel_after=N`` stops it after N frames as Esc would, for scripts and tests).
"""

from __future__ import annotations

import os
import time

import bpy
from bpy.props import IntProperty

from wetcloth.exporter.blender_extension import caches
from wetcloth.exporter.blender_extension.baking import ClothBake
from wetcloth.exporter.blender_extension.blender_scene import cloth_jobs
from wetcloth.exporter.blender_extension.frame_loop import BAKE_EVENTS, advance, tick

#: Wall-clock seconds of simulating per timer tick of the modal bake (the interface stays responsive).
TICK = 0.1


class Baking:
    """The bakes of one operator run, cloth after cloth; ``step()`` bakes one frame."""

    def __init__(self, context):
        scene = context.scene
        self.fps = scene.render.fps / scene.render.fps_base
        count = scene.frame_end - scene.frame_start + 1
        self.jobs = cloth_jobs(context)  # the scene checked whole before the last bake is touched
        for job in self.jobs:
            caches.detach(job.obj, delete_files=False)
        context.evaluated_depsgraph_get().update()  # Blender lets go of the old USD files
        self.bakes = [ClothBake(job.scene, job.cloth, job.directory, job.prefix, self.fps, scene.frame_start, count,
                                to_local=job.to_local, water_levels=job.water_levels) for job in self.jobs]
        self.total = count * len(self.bakes)
        self.done = 0
        self.started = time.perf_counter()

    @property
    def finished(self) -> bool:
        return self.done == self.total

    def step(self) -> None:
        bake = next(b for b in self.bakes if not b.finished)
        bake.step()
        self.done += 1

    def close(self) -> str:
        """Finish every cache and put it on its cloth; a line saying what was baked."""
        for job, bake in zip(self.jobs, self.bakes):
            bake.close()
            if bake.done:
                caches.attach(job.obj, str(bake.sequence.usd_path), job.prefix)
        seconds = time.perf_counter() - self.started
        names = ", ".join(f"{job.obj.name!r} ({bake.done} frames, step error up to {bake.largest_error * 1000:.2g} mm)"
                          for job, bake in zip(self.jobs, self.bakes))
        return f"Wet Cloth: baked {names} in {seconds:.1f} s"


class WETCLOTH_OT_bake(bpy.types.Operator):
    """Simulate every Wet Cloth cloth over the scene's frame range into its cache (Esc cancels, keeping
    the frames baked so far)"""

    bl_idname = "wetcloth.bake"
    bl_label = "Bake"
    bl_options = {"REGISTER"}

    cancel_after: IntProperty(name="Cancel after", default=0, min=0,
                              description="Stop as Esc does after this many frames (0: bake every frame); "
                                          "for scripts and tests")

    def _start(self, context) -> bool:
        try:
            self.baking = Baking(context)
        except (ValueError, OSError) as exc:
            self.report({"ERROR"}, str(exc))
            return False
        return True

    def _finish(self, context, stopped: str | None) -> set:
        baking, self.baking = self.baking, None  # (Blender keeps the last operator: not its simulations)
        summary = baking.close()
        context.scene.frame_set(context.scene.frame_start)
        if stopped is None:
            self.report({"INFO"}, summary)
            return {"FINISHED"}
        if stopped == "cancelled":
            self.report({"WARNING"}, f"{summary}: cancelled after {baking.done} of {baking.total} frames, "
                                     "the frames baked are kept")
            return {"CANCELLED"}
        self.report({"ERROR"}, f"{summary}; the bake stopped with an {stopped}")
        return {"CANCELLED"}

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, self.baking.total)
        stopped = None
        try:
            while not self.baking.finished and stopped is None:
                stopped = advance(self.baking, self.cancel_after)
                wm.progress_update(self.baking.done)
        finally:
            wm.progress_end()
        return self._finish(context, stopped)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        if not self._start(context):
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.progress_begin(0, self.baking.total)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type not in BAKE_EVENTS:
            return {"PASS_THROUGH"}
        stopped, status = tick(self.baking, event.type, TICK, self.cancel_after)
        wm = context.window_manager
        wm.progress_update(self.baking.done)
        context.workspace.status_text_set(status)
        if status is not None:
            return {"RUNNING_MODAL"}
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        return self._finish(context, stopped)


class WETCLOTH_OT_free_bake(bpy.types.Operator):
    """Remove the baked caches of every Wet Cloth cloth (the modifier and the cache's files)"""

    bl_idname = "wetcloth.free_bake"
    bl_label = "Free Bake"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        deleted = []
        for obj in context.scene.objects:
            if caches.cache_modifier(obj) is not None:
                deleted += caches.detach(obj)
        folders = sorted({os.path.dirname(path) for path in deleted})
        self.report({"INFO"}, f"Wet Cloth: freed the bake ({len(deleted)} files removed from "
                              f"{', '.join(folders) or 'nowhere'})")
        return {"FINISHED"}


CLASSES = (WETCLOTH_OT_bake, WETCLOTH_OT_free_bake)

register, unregister = bpy.utils.register_classes_factory(CLASSES)
