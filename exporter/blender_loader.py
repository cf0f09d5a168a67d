"""Load a wetcloth frame sequence into Blender (4.2 or newer) as one animated, render-ready object.

Run it inside Blender, either
    blender --python load_in_blender.py                         (a new scene with the cloth),
    blender shot.blend --python load_in_blender.py -- --subdivision 2 --first-frame 1001
                                                                (options after "--", see --help), or
    Text editor > Open > load_in_blender.py > Run Script,
or from Python inside Blender: ``runpy.run_path("load_in_blender.py")["load"](subdivision=2)``.
It needs no add-on.  What it builds:

* object ``<prefix>`` (e.g. ``cloth``): the cloth mesh (quads or triangles, as exported) with its
  UV map, whose geometry-nodes modifier ``wetcloth sequence`` moves every vertex to the current
  frame's position and stores the float attribute ``wetness`` (0 dry .. 1 saturated) on it
  (between frames, e.g. for motion blur, both are interpolated linearly);
* then, as the options say (defaults in ``frames.json``, key ``blender``): a Subdivision Surface
  modifier, a Solidify modifier as thick as the cloth (times a factor), smooth shading, and the
  material ``wetcloth wetness``, a Principled BSDF that darkens and turns glossier with ``wetness``;
* object ``<prefix> trajectories`` (hidden): one curve per cloth vertex with a point per frame,
  the cache the modifier reads (positions and ``wetness``; 16 bytes per vertex and frame);
* the scene's frame range and frame rate: set to the sequence's in a new file, kept in a saved
  one (option ``timeline``); the sequence starts at its own first frame (option ``first_frame``).

In a new, unsaved file Blender's untouched default cube is deleted first (the cloth would be
hidden inside it); nothing else in the scene is touched.

Everything lives in the .blend file: save it and it plays again when reopened, with no script
(the modifier does the work, no frame-change handler).  A USD sequence (``<prefix>.usd``) is
instead imported with Blender's USD importer, which plays it through a Mesh Sequence Cache
modifier and reads the velocities into the attribute ``velocity`` (Cycles' motion blur uses it);
the script then adds the same modifiers and material.  The .blend then plays the .usd from where
it is: a missing one is refused when the script loads it, and the registered text block
``wetcloth_check_caches.py`` says so in Blender's interface when the file opens (where Blender may
run the file's scripts), rather than leaving the cloth frozen with a console warning.

For OBJ frames the wetness comes back from the vertex colour (OBJ cannot carry a custom float):
the colour is matched to the exporter's colour table, so it is exact to 1/255.
"""

import argparse
import contextlib
import ctypes
import glob
import json
import os
import re
import sys
import time

import bpy
import numpy as np

SETTINGS: dict = {}  # filled in by the exporter

DRY_COLOR = (0.80, 0.77, 0.70, 1.0)  # linear RGB of the dry fabric (linen)
WET_COLOR = (0.30, 0.28, 0.25, 1.0)  # the same fabric soaked: darker
DRY_ROUGHNESS, WET_ROUGHNESS = 0.9, 0.45


# ---------------------------------------------------------------------------- options
def check_option(name, value):
    """``value`` as option ``name`` takes it (the exporter's table, SETTINGS["option_table"]), or ValueError."""
    table = SETTINGS["option_table"]
    if name not in table:
        raise ValueError(f"unknown option {name!r}; the options are {', '.join(table)}")
    spec = table[name]
    kind = spec["kind"]
    if kind == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"option {name} must be true or false, got {value!r}")
    elif kind == "choice":
        if value not in spec["choices"]:
            raise ValueError(f"option {name} must be one of {', '.join(spec['choices'])}, got {value!r}")
    elif (isinstance(value, bool) or not isinstance(value, int if kind == "int" else (int, float))
          or not spec["min"] <= value <= spec["max"]):
        raise ValueError(f"option {name} must be {'a whole number' if kind == 'int' else 'a number'} "
                         f"from {spec['min']:g} to {spec['max']:g}, got {value!r}")
    return value


def resolve_options(manifest, overrides):
    """The options in force: the exporter's, then those in frames.json (key ``blender``), then ``overrides``."""
    options = dict(SETTINGS["options"])
    for where, source in ((f"{SETTINGS['manifest']} (key 'blender'): ", manifest.get("blender") or {}),
                          ("", overrides)):
        for name, value in source.items():
            try:
                options[name] = check_option(name, value)
            except ValueError as exc:
                raise ValueError(where + str(exc)) from None
    return options


def command_line_options(argv):
    """Options given after ``--`` on Blender's command line, e.g. ``-- --subdivision 2 --no-solidify``."""
    if "--" not in argv:
        return {}
    parser = argparse.ArgumentParser(prog="blender --python load_in_blender.py --",
                                     description="Load a wetcloth frame sequence; defaults from frames.json.")
    for name, spec in SETTINGS["option_table"].items():
        flag = "--" + name.replace("_", "-")
        if spec["kind"] == "bool":
            parser.add_argument(flag, dest=name, action=argparse.BooleanOptionalAction, default=None, help=spec["help"])
        else:
            kind = {"float": float, "int": int, "choice": str}[spec["kind"]]
            parser.add_argument(flag, dest=name, type=kind, choices=spec.get("choices"), default=None,
                                help=spec["help"])
    parser.add_argument("--no-solidify", dest="solidify", action="store_const", const=0.0,
                        help="no Solidify modifier (same as --solidify 0)")
    given = {name: value for name, value in vars(parser.parse_args(argv[argv.index("--") + 1:])).items()
             if value is not None}
    for name, value in given.items():
        try:
            check_option(name, value)
        except ValueError as exc:
            parser.error(str(exc))  # usage and the one-line reason, exit status 2
    return given


# ---------------------------------------------------------------------------- finding the frames
def script_directory():
    """The folder this script was run from, if Blender tells it (``--python`` or the Text editor)."""
    candidates = []
    path = globals().get("__file__")
    if path:
        candidates.append(path)
    for text in bpy.data.texts:
        if text.filepath and os.path.basename(text.filepath) == "load_in_blender.py":
            candidates.append(bpy.path.abspath(text.filepath))
    for path in candidates:
        folder = os.path.dirname(os.path.abspath(path))
        if os.path.isfile(os.path.join(folder, SETTINGS["manifest"])):
            return folder
    return None


def read_manifest(directory):
    """``frames.json`` of the sequence, or {} if it is missing (a run that did not finish); a RuntimeError
    naming it if it is not a JSON object (edited by hand, or cut short)."""
    path = os.path.join(directory, SETTINGS["manifest"])
    if not os.path.isfile(path):
        return {}
    try:
        with open(path, encoding="utf-8") as fh:
            manifest = json.load(fh)
    except ValueError as exc:  # JSONDecodeError, UnicodeDecodeError
        raise RuntimeError(f"wetcloth: {path} is not valid JSON ({exc}): mend it, or delete it to load the "
                           "frames with the default options") from None
    if not isinstance(manifest, dict):
        raise RuntimeError(f"wetcloth: {path} is not a JSON object of the sequence's settings: mend it, or "
                           "delete it to load the frames with the default options")
    return manifest


def frame_files(directory, prefix, fmt):
    """The frame files ``<prefix>_NNNN.<fmt>`` in frame order."""
    pattern = re.compile(re.escape(prefix) + r"_(\d+)\." + re.escape(fmt) + "$")
    numbered = []
    for path in glob.glob(os.path.join(glob.escape(directory), f"{glob.escape(prefix)}_*.{fmt}")):
        match = pattern.match(os.path.basename(path))
        if match:
            numbered.append((int(match.group(1)), path))
    return [path for _, path in sorted(numbered)]


# ---------------------------------------------------------------------------- importing frames
def _flush_c_stdio():
    """Flush the C library's buffered stdout (what Blender's C++ printed), where ctypes can reach it."""
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None).fflush(None)


@contextlib.contextmanager
def quiet_stdout():
    """Standard output (file descriptor 1) goes nowhere inside the block: Blender's importers print a
    line per file ("PLY import of 'cloth_0001.ply' took 0.30 ms") from C++, past Python's sys.stdout,
    2701 lines for a 90 s towel.  Errors (standard error) still show."""
    sys.stdout.flush()
    _flush_c_stdio()
    try:
        saved = os.dup(1)
    except OSError:  # no standard output to silence
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        yield
    finally:
        _flush_c_stdio()
        os.dup2(saved, 1)
        os.close(saved)
        os.close(devnull)


def import_mesh_file(path):
    """Import one PLY or OBJ frame with Blender's own importer (its line per file silenced); return
    the new object (z up, m)."""
    before = set(bpy.data.objects)
    with quiet_stdout():
        if path.endswith(".ply"):
            bpy.ops.wm.ply_import(filepath=path, forward_axis="Y", up_axis="Z", merge_verts=False)
        else:
            bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z", validate_meshes=False,
                                  use_split_objects=False, use_split_groups=False)
    new = [ob for ob in bpy.data.objects if ob not in before and ob.type == "MESH"]
    if len(new) != 1:
        raise RuntimeError(f"importing {path} gave {len(new)} mesh objects, expected 1")
    return new[0]


def color_attribute(mesh):
    """The imported per-vertex colour attribute (PLY: ``Col``, OBJ: ``Color``), or None."""
    for attribute in mesh.color_attributes:
        if attribute.domain == "POINT":
            return attribute
    return None


def read_float(attribute, count, width):
    values = np.empty(count * width, dtype=np.float32)
    key = "value" if width == 1 else ("color" if attribute.data_type.endswith("COLOR") else "vector")
    attribute.data.foreach_get(key, values)
    return values.reshape(count, width) if width > 1 else values


def srgb_from_linear(c):
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def wetness_from_colors(rgba_linear):
    """Wetness (n,) from imported vertex colours (linear float RGBA): the index of the colour in the
    exporter's table over its last index; a colour not in the table takes the nearest entry."""
    lut = np.asarray(SETTINGS["lut"], dtype=np.int64)
    rgb = np.rint(srgb_from_linear(rgba_linear[:, :3].astype(np.float64)) * 255.0).astype(np.int64)
    lut_keys = (lut[:, 0] << 16) | (lut[:, 1] << 8) | lut[:, 2]
    keys = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    order = np.argsort(lut_keys, kind="stable")  # equal colours: the lower (drier) entry first
    sorted_keys = lut_keys[order]
    at = np.clip(np.searchsorted(sorted_keys, keys), 0, len(lut) - 1)
    index = order[at]
    missing = sorted_keys[at] != keys
    if missing.any():
        distance = ((rgb[missing][:, None, :] - lut[None, :, :]) ** 2).sum(axis=2)
        index[missing] = distance.argmin(axis=1)
    return (index / (len(lut) - 1)).astype(np.float32)


def read_frames(files):
    """Positions (N, n, 3) and wetness (N, n) of every frame, plus the first frame's faces (m, 3 or 4)
    and corner UVs (3 m or 4 m, 2)."""
    count = len(files)
    positions = wetness = None
    faces = uv = None
    started = time.time()
    for k, path in enumerate(files):
        ob = import_mesh_file(path)
        mesh = ob.data
        n = len(mesh.vertices)
        if positions is None:
            positions = np.empty((count, n, 3), dtype=np.float32)
            wetness = np.empty((count, n), dtype=np.float32)
            corners = np.empty(len(mesh.loops), dtype=np.int32)
            mesh.loops.foreach_get("vertex_index", corners)
            sizes = np.empty(len(mesh.polygons), dtype=np.int32)
            mesh.polygons.foreach_get("loop_total", sizes)
            if not (sizes == sizes[0]).all() or sizes[0] not in (3, 4):
                raise RuntimeError(f"{path}: expected triangles only or quads only")
            faces = corners.reshape(-1, int(sizes[0]))
            if mesh.uv_layers:
                uv = np.empty(len(mesh.loops) * 2, dtype=np.float32)
                mesh.uv_layers[0].data.foreach_get("uv", uv)
                uv = uv.reshape(-1, 2)
        elif n != positions.shape[1]:
            raise RuntimeError(f"{path} has {n} vertices, the first frame {positions.shape[1]}: topology must be fixed")
        co = np.empty(n * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        positions[k] = co.reshape(n, 3)
        col = color_attribute(mesh)
        if "wetness" in mesh.attributes:
            wetness[k] = read_float(mesh.attributes["wetness"], n, 1)
        elif col is not None:
            wetness[k] = wetness_from_colors(read_float(col, n, 4))
        else:
            raise RuntimeError(f"{path} has neither a wetness attribute nor vertex colours")
        bpy.data.objects.remove(ob)
        bpy.data.meshes.remove(mesh)
        if count > 50 and (k + 1) % max(1, count // 10) == 0:
            print(f"wetcloth: read {k + 1}/{count} frames ({time.time() - started:.1f} s)")
    return positions, wetness, faces, uv


# ---------------------------------------------------------------------------- building the object
def make_trajectories(name, positions, wetness):
    """A hidden curves object: one curve per vertex, point k = frame k (position, wetness)."""
    count, n, _ = positions.shape
    curves = bpy.data.hair_curves.new(name)
    curves.add_curves([count] * n)
    curves.position_data.foreach_set("vector", positions.transpose(1, 0, 2).ravel())
    wet = curves.attributes.new("wetness", "FLOAT", "POINT")
    wet.data.foreach_set("value", wetness.T.ravel())
    ob = bpy.data.objects.new(name, curves)
    bpy.context.scene.collection.objects.link(ob)
    ob.hide_set(True)
    ob.hide_render = True
    return ob


def make_cloth_mesh(name, first_positions, faces, uv):
    """The display mesh: first frame's vertices, the faces, the UV map."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(first_positions.tolist(), [], faces.tolist())
    if uv is not None:
        layer = mesh.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", uv.ravel())
    mesh.update()
    return mesh


def _node(tree, kind, x, y, **props):
    node = tree.nodes.new(kind)
    node.location = (x, y)
    for key, value in props.items():
        setattr(node, key, value)
    return node


def _math(tree, operation, x, y, a, b=None):
    """A float Math node computing ``a <operation> b``; a and b are sockets or numbers."""
    node = _node(tree, "ShaderNodeMath", x, y, operation=operation)
    for socket, value in zip(node.inputs, (a, b)):
        if value is None:
            continue
        if isinstance(value, (int, float)):
            socket.default_value = float(value)
        else:
            tree.links.new(value, socket)
    return node.outputs[0]


def make_sequence_nodes(name, trajectories, frame_count, first_frame):
    """Geometry nodes: at scene frame f, vertex i sits between points k and k + 1 of trajectory i,
    where f - first_frame = k + t (0 <= t < 1), at (1 - t) of the way; likewise its wetness.

    At whole frames (t = 0) that is point k exactly; before the first frame and after the last, the
    first and last points.  Between frames (Cycles evaluates them for deformation motion blur) the
    cloth moves in a straight line from one frame to the next.
    """
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    link = tree.links.new
    group_in = _node(tree, "NodeGroupInput", -1600, 0)
    group_out = _node(tree, "NodeGroupOutput", 1000, 0)

    # s = frame - first_frame; k = clamp(floor(s), 0, N - 1); next = min(k + 1, N - 1); t = clamp(s - k, 0, 1)
    scene_time = _node(tree, "GeometryNodeInputSceneTime", -1600, -400)
    s = _math(tree, "SUBTRACT", -1400, -400, scene_time.outputs["Frame"], first_frame)
    k = _math(tree, "MAXIMUM", -1000, -400,
              _math(tree, "MINIMUM", -1100, -400, _math(tree, "FLOOR", -1250, -400, s), frame_count - 1), 0.0)
    following = _math(tree, "MINIMUM", -850, -550, _math(tree, "ADD", -1000, -550, k, 1.0), frame_count - 1)
    t = _node(tree, "ShaderNodeMath", -850, -250, operation="SUBTRACT", use_clamp=True)
    link(s, t.inputs[0])
    link(k, t.inputs[1])
    t = t.outputs[0]

    info = _node(tree, "GeometryNodeObjectInfo", -1400, -800, transform_space="ORIGINAL")
    info.inputs["Object"].default_value = trajectories
    vertex_index = _node(tree, "GeometryNodeInputIndex", -700, -800).outputs["Index"]
    # the global index of point k (and k + 1) of each curve, evaluated on the curve domain (integers only)
    point_index = []
    for row, sort_index in enumerate((k, following)):
        points_of_curve = _node(tree, "GeometryNodePointsOfCurve", -700, -400 - 150 * row)
        link(sort_index, points_of_curve.inputs["Sort Index"])
        point_index.append(points_of_curve.outputs["Point Index"])

    def sample(value, data_type, index, x, y):
        """``value`` of point ``index`` of the curve whose index is the cloth vertex's."""
        at_point = _node(tree, "GeometryNodeFieldAtIndex", x, y, data_type=data_type, domain="POINT")
        link(index, at_point.inputs["Index"])
        link(value, at_point.inputs["Value"])
        sampled = _node(tree, "GeometryNodeSampleIndex", x + 180, y, data_type=data_type, domain="CURVE")
        link(info.outputs["Geometry"], sampled.inputs["Geometry"])
        link(at_point.outputs["Value"], sampled.inputs["Value"])
        link(vertex_index, sampled.inputs["Index"])
        return sampled.outputs["Value"]

    # position: p_k + (p_next - p_k) * t, exactly p_k at t = 0 and where p_next = p_k
    position = _node(tree, "GeometryNodeInputPosition", -500, 300).outputs[0]
    here, there = (sample(position, "FLOAT_VECTOR", index, -300, 300 - 150 * row)
                   for row, index in enumerate(point_index))
    step = _node(tree, "ShaderNodeVectorMath", 100, 300, operation="SUBTRACT")
    link(there, step.inputs[0])
    link(here, step.inputs[1])
    scaled = _node(tree, "ShaderNodeVectorMath", 250, 300, operation="SCALE")
    link(step.outputs["Vector"], scaled.inputs[0])
    link(t, scaled.inputs["Scale"])
    moved = _node(tree, "ShaderNodeVectorMath", 400, 300, operation="ADD")
    link(here, moved.inputs[0])
    link(scaled.outputs["Vector"], moved.inputs[1])
    set_position = _node(tree, "GeometryNodeSetPosition", 600, 0)
    link(group_in.outputs[0], set_position.inputs["Geometry"])
    link(moved.outputs["Vector"], set_position.inputs["Position"])

    # wetness: w_k + (w_next - w_k) * t
    named = _node(tree, "GeometryNodeInputNamedAttribute", -500, -100, data_type="FLOAT")
    named.inputs["Name"].default_value = "wetness"
    wet_here, wet_there = (sample(named.outputs["Attribute"], "FLOAT", index, -300, -100 - 150 * row)
                           for row, index in enumerate(point_index))
    wet = _math(tree, "ADD", 400, -100, wet_here,
                _math(tree, "MULTIPLY", 250, -100, _math(tree, "SUBTRACT", 100, -100, wet_there, wet_here), t))
    store = _node(tree, "GeometryNodeStoreNamedAttribute", 800, 0, data_type="FLOAT", domain="POINT")
    store.inputs["Name"].default_value = "wetness"
    link(set_position.outputs["Geometry"], store.inputs["Geometry"])
    link(wet, store.inputs["Value"])
    link(store.outputs["Geometry"], group_out.inputs[0])
    return tree


def _socket(sockets, identifier):
    return next(socket for socket in sockets if socket.identifier == identifier)


def make_material(name="wetcloth wetness"):
    """Principled BSDF whose colour darkens and roughness drops with the ``wetness`` attribute."""
    material = bpy.data.materials.get(name)
    if material is not None:
        return material
    material = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):  # Blender 5 materials always use nodes (the flag is deprecated)
        material.use_nodes = True
    tree = material.node_tree
    bsdf = next(node for node in tree.nodes if node.type == "BSDF_PRINCIPLED")
    wet = _node(tree, "ShaderNodeAttribute", -700, 200, attribute_type="GEOMETRY", attribute_name="wetness")
    mix = _node(tree, "ShaderNodeMix", -400, 300, data_type="RGBA")
    mix.inputs["Factor"].default_value = 0.0
    _socket(mix.inputs, "A_Color").default_value = DRY_COLOR
    _socket(mix.inputs, "B_Color").default_value = WET_COLOR
    gloss = _node(tree, "ShaderNodeMapRange", -400, 0)
    gloss.inputs["To Min"].default_value = DRY_ROUGHNESS
    gloss.inputs["To Max"].default_value = WET_ROUGHNESS
    tree.links.new(wet.outputs["Fac"], mix.inputs["Factor"])
    tree.links.new(_socket(mix.outputs, "Result_Color"), bsdf.inputs["Base Color"])
    tree.links.new(wet.outputs["Fac"], gloss.inputs["Value"])
    tree.links.new(gloss.outputs["Result"], bsdf.inputs["Roughness"])
    return material


def remove_default_cube():
    """Delete Blender's untouched startup cube (2 m, at the origin) from a new, unsaved file: the
    cloth, half a metre wide at z = 0, would sit hidden inside it.  A saved file is left alone."""
    cube = bpy.data.objects.get("Cube")
    if bpy.data.filepath or cube is None or cube.type != "MESH" or cube.modifiers:
        return
    if len(cube.data.vertices) != 8 or cube.location.length > 0 or tuple(cube.dimensions) != (2.0, 2.0, 2.0):
        return
    mesh = cube.data
    bpy.data.objects.remove(cube)
    if mesh.users == 0:
        bpy.data.meshes.remove(mesh)
    print("wetcloth: removed Blender's default cube (the cloth would be hidden inside it)")


def add_render_modifiers(ob, options, thickness):
    """After the sequence: Subdivision Surface, then Solidify as thick as the cloth (centred on the
    simulated sheet, which is its middle surface); smooth or flat shading."""
    if options["subdivision"] > 0:
        subdivision = ob.modifiers.new("Subdivision", "SUBSURF")
        subdivision.levels = subdivision.render_levels = options["subdivision"]
    if options["solidify"] > 0:
        if thickness:
            solidify = ob.modifiers.new("Solidify", "SOLIDIFY")
            solidify.thickness = options["solidify"] * thickness
            solidify.offset = 0.0
            solidify.use_even_offset = True
            solidify.use_quality_normals = True
        else:
            print("wetcloth: frames.json gives no cloth thickness (no scene); no Solidify modifier")
    if options["smooth"]:
        ob.data.shade_smooth()
    else:
        ob.data.shade_flat()


def apply_timeline(mode, fps, first_frame, frame_count):
    """Set the scene's fps and frame range to the sequence's ('set', or 'auto' in a new file), or keep
    them ('keep', or 'auto' in a saved file) and say where they differ from the sequence."""
    scene = bpy.context.scene
    last_frame = first_frame + max(frame_count, 1) - 1
    if mode == "set" or (mode == "auto" and not bpy.data.filepath):
        whole = max(1, round(fps))
        scene.render.fps = whole
        scene.render.fps_base = whole / fps
        scene.frame_start = first_frame
        scene.frame_end = last_frame
        scene.frame_set(first_frame)
        return
    scene_fps = scene.render.fps / scene.render.fps_base
    if abs(scene_fps - fps) > 1e-6 * fps:
        print(f"wetcloth: the scene plays at {scene_fps:g} fps, the sequence was written at {fps:g} fps: "
              "it plays faster or slower than simulated (option timeline=set sets the scene's fps)")
    if scene.frame_start > first_frame or scene.frame_end < last_frame:
        print(f"wetcloth: the sequence covers frames {first_frame}..{last_frame}, the scene's range is "
              f"{scene.frame_start}..{scene.frame_end} (kept)")


def finish(ob, options, manifest, fps, first_frame, frame_count):
    """What both kinds of sequence get: the render modifiers, shading, material and timeline."""
    add_render_modifiers(ob, options, (manifest.get("scene") or {}).get("thickness"))
    if options["material"]:
        ob.data.materials.append(make_material())
    apply_timeline(options["timeline"], fps, first_frame, frame_count)


# ---------------------------------------------------------------------------- the USD cache
#: A text block registered as a module (Blender runs it when the file opens, where it may run the
#: file's scripts): it says in the interface when a USD cache the file plays is missing, which else
#: leaves the cloth frozen with only a console warning.
CACHE_CHECK = "wetcloth_check_caches.py"
CACHE_CHECK_SOURCE = '''"""wetcloth: say when a USD cache this file plays is missing (the cloth would stand still).

Registered (Text > Register): Blender runs it when the file opens, if it may run the file's scripts
(Preferences > Save & Load > Auto Run Python Scripts, or "Allow Execution" when it asks)."""
import os

import bpy


def missing_caches():
    """(cache name, absolute path) of every cache file that is not on disk."""
    found = []
    for cache in bpy.data.cache_files:
        path = bpy.path.abspath(cache.filepath)
        if not os.path.isfile(path):
            found.append((cache.name, path))
    return found


def report(problems):
    lines = [f"USD cache missing: {path} (cache {name!r}): the cloth stands still. Put the file back, or "
             "point the cache at it (Mesh Sequence Cache modifier > Cache File > File Path)."
             for name, path in problems]
    for line in lines:
        print("wetcloth: " + line)
    bpy.app.driver_namespace["wetcloth_missing_caches"] = problems

    def popup():
        wm = bpy.context.window_manager
        if wm is not None and wm.windows:
            wm.popup_menu(lambda menu, context: [menu.layout.label(text=line) for line in lines],
                          title="wetcloth: USD cache missing", icon="ERROR")
        return None

    if not bpy.app.background:
        bpy.app.timers.register(popup, first_interval=0.5)


problems = missing_caches()
bpy.app.driver_namespace["wetcloth_missing_caches"] = problems
if problems:
    report(problems)
'''


def register_cache_check():
    """Put the cache check in the file (as a registered text block) and run it once now."""
    text = bpy.data.texts.get(CACHE_CHECK) or bpy.data.texts.new(CACHE_CHECK)
    text.clear()
    text.write(CACHE_CHECK_SOURCE)
    text.use_module = True
    exec(compile(CACHE_CHECK_SOURCE, CACHE_CHECK, "exec"), {"__name__": CACHE_CHECK})


# ---------------------------------------------------------------------------- entry points
def load_usd(directory, manifest, name, options, fps):
    """Import ``<prefix>.usd`` (played by a Mesh Sequence Cache modifier), shifted to the option's first frame."""
    path = os.path.join(directory, SETTINGS["usd_file"])
    scene = bpy.context.scene
    kept_range = scene.frame_start, scene.frame_end
    before = set(bpy.data.objects)
    bpy.ops.wm.usd_import(filepath=path, set_frame_range=True, read_mesh_attributes=True,
                          read_mesh_colors=True, read_mesh_uvs=True, import_materials=False)
    stage_range = scene.frame_start, scene.frame_end  # the stage's time codes, which the importer sets
    scene.frame_start, scene.frame_end = kept_range
    meshes = [ob for ob in bpy.data.objects if ob not in before and ob.type == "MESH"]
    if len(meshes) != 1:
        raise RuntimeError(f"importing {path} gave {len(meshes)} mesh objects, expected 1")
    ob = meshes[0]
    ob.name = name
    first_frame = options["first_frame"]
    cache = next(modifier for modifier in ob.modifiers if modifier.type == "MESH_SEQUENCE_CACHE")
    cache.cache_file.frame_offset = first_frame - stage_range[0]  # subtracted from the scene frame
    frame_count = manifest.get("frame_count") or stage_range[1] - stage_range[0] + 1
    finish(ob, options, manifest, fps, first_frame, frame_count)
    register_cache_check()  # when the file opens again, a moved cache is said in the interface
    return ob


def load(directory=None, name=None, **options):
    """Build the animated cloth from the frames in ``directory`` (default: beside this script).

    ``options`` change those of frames.json (key ``blender``): solidify (factor on the cloth's
    thickness, 0: none), subdivision (levels, 0: none), smooth (bool), material (bool),
    first_frame (scene frame of the sequence's first frame), timeline ('auto', 'set' or 'keep').
    """
    directory = directory or script_directory() or SETTINGS["directory"]
    manifest = read_manifest(directory)
    options = resolve_options(manifest, options)
    name = name or SETTINGS["prefix"]
    fps = float(manifest.get("fps", SETTINGS["fps"]))
    first_frame = options["first_frame"]
    usd = os.path.join(directory, SETTINGS["usd_file"]) if SETTINGS["format"] == "usd" else None
    if usd is not None and not os.path.isfile(usd):  # refused before the scene is touched
        raise RuntimeError(f"wetcloth: the USD cache {usd} is missing: nothing to play (was the .usd moved or "
                           "deleted?)")
    remove_default_cube()
    if SETTINGS["format"] == "usd":
        return load_usd(directory, manifest, name, options, fps)
    files = frame_files(directory, SETTINGS["prefix"], SETTINGS["format"])
    if not files:
        raise RuntimeError(f"no {SETTINGS['prefix']}_NNNN.{SETTINGS['format']} frames in {directory}")
    started = time.time()
    positions, wetness, faces, uv = read_frames(files)
    trajectories = make_trajectories(f"{name} trajectories", positions, wetness)
    mesh = make_cloth_mesh(name, positions[0], faces, uv)
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    modifier = ob.modifiers.new("wetcloth sequence", "NODES")
    modifier.node_group = make_sequence_nodes("wetcloth sequence", trajectories, len(files), first_frame)
    finish(ob, options, manifest, fps, first_frame, len(files))
    print(f"wetcloth: {len(files)} frames of {positions.shape[1]} vertices from {directory} "
          f"as object '{ob.name}' at {fps:g} fps from frame {first_frame} ({time.time() - started:.1f} s)")
    return ob


if __name__ == "__main__":
    load(**command_line_options(sys.argv))
