"""Denser copies of real rigged characters, made with Blender (Debian's `blender`, not a build or
test dependency): the same rig, skin and clips on a subdivided surface, so that the methods and
the memory can be measured at the 14k–112k triangles of production characters, which no bundled
or Debian character reaches (docs/benchmarks.md, "Dense characters").

    blender --background --python bench/real/densify.py -- IN.glb OUT.glb LEVELS [SIMPLE]

Each mesh is welded first (vertices at equal positions merged, as skelcd welds them, so that the
split copies along a seam subdivide as one surface and the result stays closed where the input
was), its shape keys dropped (skelcd animates node transforms only), then subdivided LEVELS times
(Catmull-Clark; SIMPLE keeps the input's surface and only splits it) with its vertex groups —
the skin weights — interpolated by Blender, and the scene exported as glTF binary with its skins
and clips. A triangle becomes 6 triangles at level 1 and 24 at level 2.

Blender 3.4's glTF add-on uses `numpy.bool`, which Debian 12's numpy 1.24 no longer has: the
alias is set back before the add-on runs.
"""
import sys
import warnings

import bpy
import numpy

with warnings.catch_warnings():
    warnings.simplefilter("ignore", FutureWarning)
    if not hasattr(numpy, "bool"):
        numpy.bool = bool


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) not in (3, 4):
        sys.exit("usage: blender --background --python densify.py -- IN.glb OUT.glb LEVELS [SIMPLE]")
    source, target, levels = argv[0], argv[1], int(argv[2])
    kind = "SIMPLE" if len(argv) == 4 and argv[3].upper() == "SIMPLE" else "CATMULL_CLARK"
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=source, merge_vertices=True)
    for ob in list(bpy.context.scene.objects):
        if ob.type != "MESH":
            continue
        bpy.context.view_layer.objects.active = ob
        for other in bpy.context.selected_objects:
            other.select_set(False)
        ob.select_set(True)
        if ob.data.shape_keys is not None:
            ob.shape_key_clear()
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        bpy.ops.mesh.remove_doubles(threshold=0.0)
        bpy.ops.object.mode_set(mode="OBJECT")
        modifier = ob.modifiers.new("Dense", "SUBSURF")
        modifier.levels = levels
        modifier.render_levels = levels
        modifier.subdivision_type = kind
        # First in the stack, before the armature: the rest pose is subdivided, not a posed one.
        bpy.ops.object.modifier_move_to_index(modifier="Dense", index=0)
        bpy.ops.object.modifier_apply(modifier="Dense")
        print(f"densify.py: {ob.name}: {len(ob.data.polygons)} faces")
    bpy.ops.export_scene.gltf(filepath=target, export_format="GLB", export_skins=True,
                              export_animations=True)


main()
