"""``bpy.ops.wetcloth.bake()`` and ``bpy.ops.wetcloth.free_bake()``.

The bake simulates every Cloth object over the scene's frame range at its fps.  From the interface
it runs as a modal operator: frames for TICK s per timer tick (frame_loop.tick), progress in the
status bar, Esc cancels and keeps the frames baked so far; one bake runs at a time.  From scripts and in
background mode it runs to the end at once (``cancel_after=N`` stops it after N frames as Esc would, for
scripts and tests).
"""

from __future__ import annotations

import os
import sys
import time

import bpy
from bpy.props import IntProperty

from wetcloth.exporter import check_directory
from wetcloth.exporter.blender_extension import caches
from wetcloth.exporter.blender_extension.baking import ClothBake
from wetcloth.exporter.blender_extension.blender_scene import cache_directory, cloth_jobs
from wetcloth.exporter.blender_extension.frame_loop import BAKE_EVENTS, advance, tick

#: Wall-clock seconds of simulating per timer tick of the modal bake (the interface stays responsive).
TICK = 0.1


def _exists(obj) -> bool:
    """False for an object deleted since the bake started (Blender's reference to it is dead)."""
    try:
        obj.name
    except ReferenceError:
        return False
    return True


class Baking:
    """The bakes of one operator run, cloth after cloth; ``step()`` bakes one frame.  A cloth's previous
    bake is replaced when its own bake starts: a cloth not reached keeps it.  One Baking runs at a time."""

    #: The Baking under way, until its ``close()``.
    running = None

    def __init__(self, context):
        if Baking.running is not None:
            raise ValueError("a bake is running: wait for it to end (Esc cancels it), then bake again")
        scene = context.scene
        self.fps = scene.render.fps / scene.render.fps_base
        self.frame_start = scene.frame_start
        self.count = scene.frame_end - scene.frame_start + 1
        self.jobs = cloth_jobs(context)  # the scene checked whole before the last bake is touched
        caches.check_folder(cache_directory(scene), scene.wetcloth.cache_directory)
        self.names = [job.obj.name for job in self.jobs]
        for job in self.jobs:
            check_directory(job.directory, overwrite=True)  # a file there, or files not of a bake: refused now
        self.bakes = []  # of the cloths reached, in order
        self.total = self.count * len(self.jobs)
        self.done = 0
        self.started = time.perf_counter()
        Baking.running = self

    @property
    def finished(self) -> bool:
        return self.done == self.total

    def _begin(self, job) -> None:
        """Start ``job``'s bake: its previous bake removed (the files replaced by the new ones)."""
        caches.release(job.obj, os.path.join(job.directory, f"{job.prefix}.usd"))
        self.bakes.append(ClothBake(job.scene, job.cloth, job.directory, job.prefix, self.fps, self.frame_start,
                                    self.count, to_local=job.to_local, water_levels=job.water_levels))

    def step(self) -> None:
        """Bake the next frame; ValueError or OSError naming the cloth if it cannot."""
        index = len(self.bakes) - 1 if self.bakes and not self.bakes[-1].finished else len(self.bakes)
        if not _exists(self.jobs[index].obj):
            raise ValueError(f"cloth {self.names[index]!r} was deleted during the bake")
        if index == len(self.bakes):
            self._begin(self.jobs[index])
        bake = self.bakes[index]
        try:
            bake.step()
        except RuntimeError as exc:  # USD's errors (pxr.Tf.ErrorException: its args are Tf.Errors)
            said = "; ".join(getattr(error, "commentary", str(error)) for error in exc.args)
            raise OSError(f"cloth {self.names[index]!r}: cannot write its cache {bake.sequence.usd_path} (USD: "
                          f"{said}); let go of the file where it is open, then bake again") from None
        self.done += 1

    def _said(self, index: int) -> str:
        """What became of cloth ``index``."""
        name, obj = self.names[index], self.jobs[index].obj
        if not _exists(obj):
            frames = f"frames baked {self.bakes[index].done}, left in {self.bakes[index].sequence.usd_path}" \
                if index < len(self.bakes) else "not baked"
            return f"{name!r} (deleted during the bake: {frames})"
        if index >= len(self.bakes):
            kept = "its previous bake is kept" if caches.cache_modifier(obj) is not None else "not baked"
            return f"{name!r} (not reached: {kept})"
        bake = self.bakes[index]
        if not bake.done:
            return f"{name!r} (no frame baked: its previous bake is removed)"
        frames = f"{bake.done} frames" if bake.finished else f"{bake.done} of {bake.frame_count} frames kept"
        return f"{name!r} ({frames}, step error up to {bake.largest_error * 1000:.2g} mm)"

    def close(self) -> str:
        """Finish every cache begun and put it on its cloth (if still there); a line saying what became of
        each cloth.  Nothing stays open, whatever fails."""
        try:
            for job, bake in zip(self.jobs, self.bakes):
                bake.close()
                if bake.done and _exists(job.obj):
                    caches.attach(job.obj, str(bake.sequence.usd_path), job.prefix)
        finally:
            for bake in self.bakes:
                bake.sequence.close(complete=False)  # (no-op for those closed above)
            Baking.running = None
        seconds = time.perf_counter() - self.started
        names = ", ".join(self._said(index) for index in range(len(self.jobs)))
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

    def _abandon(self) -> None:
        """Close the bake after an unexpected error or when Blender drops the modal bake: nothing stays
        open and the next bake may start."""
        baking, self.baking = self.baking, None
        if baking is not None:
            print(baking.close(), file=sys.stderr)

    def _finish(self, context, stopped: str | None) -> set:
        baking, self.baking = self.baking, None  # (Blender keeps the last operator: not its simulations)
        summary = baking.close()
        context.scene.frame_set(context.scene.frame_start)
        if stopped is None:
            self.report({"INFO"}, summary)
            return {"FINISHED"}
        if stopped == "cancelled":
            self.report({"WARNING"}, f"{summary}: cancelled after {baking.done} of {baking.total} frames")
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
        except BaseException:
            self._abandon()
            raise
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
        try:
            stopped, status = tick(self.baking, event.type, TICK, self.cancel_after)
        except BaseException:
            self.cancel(context)
            raise
        wm = context.window_manager
        wm.progress_update(self.baking.done)
        context.workspace.status_text_set(status)
        if status is not None:
            return {"RUNNING_MODAL"}
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        return self._finish(context, stopped)

    def cancel(self, context):
        """Blender drops the modal bake (a file loaded, the window closed): close it."""
        context.window_manager.event_timer_remove(self._timer)
        context.window_manager.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        self._abandon()


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
