"""Load a wetcloth frame sequence into Blender (4.2 or newer) as one animated object.

Run it inside Blender, either
    blender --python load_in_blender.py            (a new scene with the cloth), or
    Text editor > Open > load_in_blender.py > Run Script.
It needs no add-on.  What it builds:

* object ``<prefix>`` (e.g. ``cloth``): the cloth mesh with its UV map, smooth shaded, whose
  geometry-nodes modifier ``wetcloth sequence`` moves every vertex to the current frame's
  position and stores the float attribute ``wetness`` (0 dry .. 1 saturated) on it;
* object ``<prefix> trajectories`` (hidden): one curve per cloth vertex with a point per frame,
  the cache the modifier reads (positions and ``wetness``; 16 bytes per vertex and frame);
* material ``wetcloth wetness``: a Principled BSDF that darkens and turns glossier with ``wetness``;
* the scene's frame range (1 .. frame count) and frame rate (the sequence's fps).

In a new, unsaved file Blender's untouched default cube is deleted first (the cloth would be
hidden inside it); nothing else in the scene is touched.

Everything lives in the .blend file: save it and it plays again when reopened, with no script
(the modifier does the work, no frame-change handler).  A USD sequence (``<prefix>.usd``) is
instead imported with Blender's USD importer, which plays it through a Mesh Sequence Cache
modifier; the script then adds the material.

For OBJ frames the wetness comes back from the vertex colour (OBJ cannot carry a custom float):
the colour is matched to the exporter's colour table, so it is exact to 1/255.
"""

import glob
import json
import os
import re
import time

import bpy
import numpy as np

SETTINGS: dict = {}  # filled in by the exporter

DRY_COLOR = (0.80, 0.77, 0.70, 1.0)  # linear RGB of the dry fabric (linen)
WET_COLOR = (0.30, 0.28, 0.25, 1.0)  # the same fabric soaked: darker
DRY_ROUGHNESS, WET_ROUGHNESS = 0.9, 0.45


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
    """``frames.json`` of the sequence, or {} if it is missing (a run that did not finish)."""
    path = os.path.join(directory, SETTINGS["manifest"])
    if not os.path.isfile(path):
        return {}
    with open(path) as fh:
        return json.load(fh)


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
def import_mesh_file(path):
    """Import one PLY or OBJ frame with Blender's own importer; return the new object (z up, m)."""
    before = set(bpy.data.objects)
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
    """Positions (N, n, 3) and wetness (N, n) of every frame, plus the first frame's triangles (m, 3)
    and corner UVs (3 m, 2)."""
    count = len(files)
    positions = wetness = None
    triangles = uv = None
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
            if (sizes != 3).any():
                raise RuntimeError(f"{path}: expected triangles only")
            triangles = corners.reshape(-1, 3)
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
    return positions, wetness, triangles, uv


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


def make_cloth_mesh(name, first_positions, triangles, uv):
    """The display mesh: first frame's vertices, the triangles, the UV map, smooth shading."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(first_positions.tolist(), [], triangles.tolist())
    if uv is not None:
        layer = mesh.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", uv.ravel())
    mesh.polygons.foreach_set("use_smooth", np.ones(len(mesh.polygons), dtype=bool))
    mesh.update()
    return mesh


def _node(tree, kind, x, y, **props):
    node = tree.nodes.new(kind)
    node.location = (x, y)
    for key, value in props.items():
        setattr(node, key, value)
    return node


def make_sequence_nodes(name, trajectories, frame_count, first_frame):
    """Geometry nodes: at scene frame f, vertex i takes point (f - first_frame) of trajectory i."""
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    link = tree.links.new
    group_in = _node(tree, "NodeGroupInput", -1400, 0)
    group_out = _node(tree, "NodeGroupOutput", 800, 0)

    # frame index k = clamp(floor(frame - first_frame), 0, frame_count - 1)
    scene_time = _node(tree, "GeometryNodeInputSceneTime", -1400, -400)
    shift = _node(tree, "ShaderNodeMath", -1200, -400, operation="SUBTRACT")
    shift.inputs[1].default_value = float(first_frame)
    floor = _node(tree, "ShaderNodeMath", -1040, -400, operation="FLOOR")
    upper = _node(tree, "ShaderNodeMath", -880, -400, operation="MINIMUM")
    upper.inputs[1].default_value = float(frame_count - 1)
    lower = _node(tree, "ShaderNodeMath", -720, -400, operation="MAXIMUM")
    lower.inputs[1].default_value = 0.0
    link(scene_time.outputs["Frame"], shift.inputs[0])
    link(shift.outputs[0], floor.inputs[0])
    link(floor.outputs[0], upper.inputs[0])
    link(upper.outputs[0], lower.inputs[0])

    info = _node(tree, "GeometryNodeObjectInfo", -1200, -700, transform_space="ORIGINAL")
    info.inputs["Object"].default_value = trajectories
    # the global index of point k of each curve, evaluated on the curve domain (integers only)
    points_of_curve = _node(tree, "GeometryNodePointsOfCurve", -560, -400)
    link(lower.outputs[0], points_of_curve.inputs["Sort Index"])
    vertex_index = _node(tree, "GeometryNodeInputIndex", -560, -700)

    geometry = group_in.outputs[0]
    x = -300
    fields = [
        ("FLOAT_VECTOR", _node(tree, "GeometryNodeInputPosition", x - 300, 200).outputs[0], None),
        ("FLOAT", None, "wetness"),
    ]
    for data_type, value, attribute in fields:
        if value is None:
            named = _node(tree, "GeometryNodeInputNamedAttribute", x - 300, 200, data_type=data_type)
            named.inputs["Name"].default_value = attribute
            value = named.outputs["Attribute"]
        at_point = _node(tree, "GeometryNodeFieldAtIndex", x - 100, 200, data_type=data_type, domain="POINT")
        link(points_of_curve.outputs["Point Index"], at_point.inputs["Index"])
        link(value, at_point.inputs["Value"])
        sample = _node(tree, "GeometryNodeSampleIndex", x + 100, 200, data_type=data_type, domain="CURVE")
        link(info.outputs["Geometry"], sample.inputs["Geometry"])
        link(at_point.outputs["Value"], sample.inputs["Value"])
        link(vertex_index.outputs["Index"], sample.inputs["Index"])
        if attribute is None:
            setter = _node(tree, "GeometryNodeSetPosition", x + 300, 0)
            link(sample.outputs["Value"], setter.inputs["Position"])
        else:
            setter = _node(tree, "GeometryNodeStoreNamedAttribute", x + 300, 0, data_type=data_type, domain="POINT")
            setter.inputs["Name"].default_value = attribute
            link(sample.outputs["Value"], setter.inputs["Value"])
        link(geometry, setter.inputs["Geometry"])
        geometry = setter.outputs["Geometry"]
        x += 350
    link(geometry, group_out.inputs[0])
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


def set_timeline(fps, first_frame, frame_count):
    scene = bpy.context.scene
    whole = max(1, round(fps))
    scene.render.fps = whole
    scene.render.fps_base = whole / fps
    scene.frame_start = first_frame
    scene.frame_end = first_frame + max(frame_count, 1) - 1
    scene.frame_set(first_frame)


# ---------------------------------------------------------------------------- entry points
def load_usd(directory, manifest, name):
    path = os.path.join(directory, SETTINGS["usd_file"])
    before = set(bpy.data.objects)
    bpy.ops.wm.usd_import(filepath=path, set_frame_range=True, read_mesh_attributes=True,
                          read_mesh_colors=True, read_mesh_uvs=True, import_materials=False)
    meshes = [ob for ob in bpy.data.objects if ob not in before and ob.type == "MESH"]
    if len(meshes) != 1:
        raise RuntimeError(f"importing {path} gave {len(meshes)} mesh objects, expected 1")
    ob = meshes[0]
    ob.name = name
    ob.data.materials.append(make_material())
    frame_count = manifest.get("frame_count") or bpy.context.scene.frame_end
    set_timeline(float(manifest.get("fps", SETTINGS["fps"])), SETTINGS["first_frame"], frame_count)
    return ob


def load(directory=None, name=None):
    """Build the animated cloth from the frames in ``directory`` (default: beside this script)."""
    directory = directory or script_directory() or SETTINGS["directory"]
    manifest = read_manifest(directory)
    name = name or SETTINGS["prefix"]
    fps = float(manifest.get("fps", SETTINGS["fps"]))
    first_frame = SETTINGS["first_frame"]
    remove_default_cube()
    if SETTINGS["format"] == "usd":
        return load_usd(directory, manifest, name)
    files = frame_files(directory, SETTINGS["prefix"], SETTINGS["format"])
    if not files:
        raise RuntimeError(f"no {SETTINGS['prefix']}_NNNN.{SETTINGS['format']} frames in {directory}")
    started = time.time()
    positions, wetness, triangles, uv = read_frames(files)
    trajectories = make_trajectories(f"{name} trajectories", positions, wetness)
    mesh = make_cloth_mesh(name, positions[0], triangles, uv)
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    modifier = ob.modifiers.new("wetcloth sequence", "NODES")
    modifier.node_group = make_sequence_nodes("wetcloth sequence", trajectories, len(files), first_frame)
    mesh.materials.append(make_material())
    set_timeline(fps, first_frame, len(files))
    print(f"wetcloth: {len(files)} frames of {positions.shape[1]} vertices from {directory} "
          f"as object '{ob.name}' at {fps:g} fps ({time.time() - started:.1f} s)")
    return ob


if __name__ == "__main__":
    load()
