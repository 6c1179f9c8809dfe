"""make_plates.py -- build nprfx's sample plates procedurally in Blender (3.4, Cycles CPU).

Run headless from the repository root (about 80 s on 2 cores; samples/blender/README.md):

    blender -b --factory-startup --python samples/blender/make_plates.py -- --out samples/plates

Three shots, frames 1..24, 320x180, multilayer OpenEXR (half float, ZIP), no .blend needed:

  crossing  rigid objects crossing in front of each other (occlusion/disocclusion) in front of a
            ground and a backdrop; still camera.  Cube 1 (accelerating to the right, in front),
            Sphere 2 (to the left, behind), Torus 3 (rising, accelerating), Ground 4, Backdrop 5.
  dolly     the camera dollies from 16 to 4 units from Pillar 1 (4x scale change); Ball 2 on
            Block 3, Crate 4, Ground 5; sky (index 0) above the horizon.
  deform    Sheet 1 (Wave modifier), Ball 2 (animated squash/stretch shape key), Bar 3 (animated
            Simple Deform twist), Ground 4, Backdrop 5; still camera.  P moves, Pref stays fixed.

Passes (layer "ViewLayer"; channel names exactly as in the files):
  Combined.R/G/B/A, Depth.Z, DiffCol.R/G/B, DiffDir.R/G/B, IndexOB.X, Normal.X/Y/Z,
  Position.X/Y/Z, Pref.R/G/B/A, UV.A/U/V, Vector.X/Y/Z/W
Pref is a shader AOV (colour) = rest object-space position, stored as the point attribute "rest"
on every mesh before any shape key/modifier and read with an Attribute node, so it stays on the
surface of deforming meshes.  Pref.A (like UV.A) is the pixel's surface coverage.
Blender writes the data passes (Depth, IndexOB, Normal, Position, UV, Vector) as float32 even when
half is asked for; the script then converts every channel to half with oiiotool (--keep-float
skips this).  <shot>/<shot>.json holds the object pass indices, the camera (focal length in
pixels) and the camera/object matrix_world for every frame 0..N+1 (ground truth for tests).

Conventions measured on these renders (samples/plates/README.md; measure_plates.py re-measures):
  Vector.XY = position at frame i-1 minus position at frame i, Vector.ZW = position at frame i
  minus position at frame i+1, in pixels, y axis UP.  In nprfx's y-down convention:
      motion_prev = (+Vector.X, -Vector.Y)      motion_next = (-Vector.Z, +Vector.W)
  Depth.Z is view-space z (distance along the camera axis), background 1e10 in Blender's float
  output, +inf after the half conversion.  Depth, Position and IndexOB are one sample through the
  pixel centre (not filtered); Vector, Normal, UV, Pref and the colour passes are filtered
  (Blackman-Harris, 1.5 px), so they blend the two sides of a silhouette.

Options after "--": --out DIR, --shots crossing,dolly,deform, --frames N, --samples N,
--res WxH, --threads N, --frame-range A-B (render a subset), --keep-float.
"""

import argparse
import json
import math
import os
import sys
import time

import bpy
import bmesh
from mathutils import Vector

# --------------------------------------------------------------------------------------------
# options


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="make_plates.py")
    ap.add_argument("--out", default="samples/plates")
    ap.add_argument("--shots", default="crossing,dolly,deform")
    ap.add_argument("--frames", type=int, default=24)
    ap.add_argument("--samples", type=int, default=24)
    ap.add_argument("--res", default="320x180")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--frame-range", default="", help="A-B: render only these frames")
    ap.add_argument("--keep-float", action="store_true",
                    help="keep Blender's own output (data passes stay float32) instead of "
                         "converting every channel to half with oiiotool")
    return ap.parse_args(argv)


# --------------------------------------------------------------------------------------------
# scene helpers


def clear_scene():
    for coll in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights,
                 bpy.data.cameras, bpy.data.actions, bpy.data.textures, bpy.data.worlds):
        for block in list(coll):
            coll.remove(block)


def add_mesh_object(name, bm, pass_index, location=(0, 0, 0), smooth=False):
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    if smooth:
        for p in me.polygons:
            p.use_smooth = True
    # rest position (object space) as a point attribute: this is what the Pref AOV reads, so that
    # Pref stays on the surface when shape keys or deform modifiers move the vertices.
    attr = me.attributes.new("rest", "FLOAT_VECTOR", "POINT")
    co = [0.0] * (3 * len(me.vertices))
    me.vertices.foreach_get("co", co)
    attr.data.foreach_set("vector", co)
    ob = bpy.data.objects.new(name, me)
    ob.location = location
    ob.pass_index = pass_index
    bpy.context.scene.collection.objects.link(ob)
    return ob


def new_bm():
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")     # calc_uvs=True only fills an existing UV layer
    return bm


def bm_cube(size):
    bm = new_bm()
    bmesh.ops.create_cube(bm, size=size, calc_uvs=True)
    return bm


def bm_sphere(radius, segs=48, rings=24):
    bm = new_bm()
    bmesh.ops.create_uvsphere(bm, u_segments=segs, v_segments=rings, radius=radius, calc_uvs=True)
    return bm


def bm_grid(size_x, size_y, nx, ny):
    bm = new_bm()
    bmesh.ops.create_grid(bm, x_segments=nx, y_segments=ny, size=0.5, calc_uvs=True)
    bmesh.ops.scale(bm, vec=(size_x, size_y, 1.0), verts=bm.verts)
    return bm


def bm_cylinder(radius, depth, segs=32, cuts=0):
    bm = new_bm()
    bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=segs, radius1=radius,
                          radius2=radius, depth=depth, calc_uvs=True)
    if cuts:
        side = [e for e in bm.edges
                if abs(e.verts[0].co.z - e.verts[1].co.z) > 0.5 * depth]
        bmesh.ops.subdivide_edges(bm, edges=side, cuts=cuts, use_grid_fill=True)
    return bm


def bm_torus(major, minor, nu=48, nv=20):
    bm = bmesh.new()
    uv_layer = bm.loops.layers.uv.new("UVMap")
    verts = []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        row = []
        for j in range(nv):
            v = 2 * math.pi * j / nv
            r = major + minor * math.cos(v)
            row.append(bm.verts.new((r * math.cos(u), r * math.sin(u), minor * math.sin(v))))
        verts.append(row)
    for i in range(nu):
        for j in range(nv):
            i1, j1 = (i + 1) % nu, (j + 1) % nv
            f = bm.faces.new((verts[i][j], verts[i1][j], verts[i1][j1], verts[i][j1]))
            uvs = ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1))
            for loop, (a, b) in zip(f.loops, uvs):
                loop[uv_layer].uv = (a / nu, b / nv)
    bm.normal_update()
    return bm


AMBIENT = (0.22, 0.25, 0.32)     # bluish ambient fill, as emission


def make_material(name, col_a, col_b, checker_scale, noise_scale=1.5, roughness=0.55,
                  specular=0.3):
    """Principled BSDF; base colour = 3D checker on the rest position times two-tone blotches
    (a noise texture through a CONSTANT colour ramp).  Piecewise-constant albedo: smooth or
    high-frequency texture would alias into per-pixel sample noise at 24 samples and make the
    EXRs several times larger.  The rest position is also written to the shader AOV 'Pref'."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    # the ambient emission must not turn the surfaces into lights (noise from light selection)
    if hasattr(mat.cycles, "sample_as_light"):
        mat.cycles.sample_as_light = False
    else:
        mat.cycles.emission_sampling = "NONE"
    nt = mat.node_tree
    nodes, links = nt.nodes, nt.links
    for n in list(nodes):
        nodes.remove(n)
    out = nodes.new("ShaderNodeOutputMaterial")
    out.location = (900, 0)
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.location = (600, 0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Specular"].default_value = specular
    # ambient fill = base colour * AMBIENT as emission: deterministic, unlike a second light
    amb = nodes.new("ShaderNodeMixRGB")
    amb.location = (600, 200)
    amb.blend_type = "MULTIPLY"
    amb.inputs["Fac"].default_value = 1.0
    amb.inputs["Color2"].default_value = (*AMBIENT, 1.0)
    emis = nodes.new("ShaderNodeEmission")
    emis.location = (750, 200)
    add = nodes.new("ShaderNodeAddShader")
    add.location = (800, 0)
    links.new(amb.outputs["Color"], emis.inputs["Color"])
    camray = nodes.new("ShaderNodeLightPath")     # emission for camera rays only: without this
    camray.location = (600, 350)                  # the DiffDir/Combined passes get grainy
    links.new(camray.outputs["Is Camera Ray"], emis.inputs["Strength"])
    links.new(bsdf.outputs["BSDF"], add.inputs[0])
    links.new(emis.outputs["Emission"], add.inputs[1])
    links.new(add.outputs["Shader"], out.inputs["Surface"])

    rest = nodes.new("ShaderNodeAttribute")
    rest.attribute_type = "GEOMETRY"
    rest.attribute_name = "rest"
    rest.location = (-600, 0)

    checker = nodes.new("ShaderNodeTexChecker")
    checker.location = (-200, 150)
    checker.inputs["Scale"].default_value = checker_scale
    checker.inputs["Color1"].default_value = (*col_a, 1.0)
    checker.inputs["Color2"].default_value = (*col_b, 1.0)
    links.new(rest.outputs["Vector"], checker.inputs["Vector"])

    noise = nodes.new("ShaderNodeTexNoise")
    noise.location = (-200, -150)
    noise.inputs["Scale"].default_value = noise_scale
    noise.inputs["Detail"].default_value = 1.0
    links.new(rest.outputs["Vector"], noise.inputs["Vector"])

    mix = nodes.new("ShaderNodeMixRGB")
    mix.location = (200, 0)
    mix.blend_type = "MULTIPLY"
    mix.inputs["Fac"].default_value = 1.0
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.location = (0, -150)
    ramp.color_ramp.interpolation = "CONSTANT"
    ramp.color_ramp.elements[0].position = 0.0
    ramp.color_ramp.elements[0].color = (0.72, 0.72, 0.72, 1)
    ramp.color_ramp.elements[1].position = 0.5
    ramp.color_ramp.elements[1].color = (1, 1, 1, 1)
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(checker.outputs["Color"], mix.inputs["Color1"])
    links.new(ramp.outputs["Color"], mix.inputs["Color2"])
    links.new(mix.outputs["Color"], bsdf.inputs["Base Color"])
    links.new(mix.outputs["Color"], amb.inputs["Color1"])

    aov = nodes.new("ShaderNodeOutputAOV")
    aov.location = (600, -300)
    if hasattr(aov, "aov_name"):
        aov.aov_name = "Pref"
    else:
        aov.name = "Pref"
    links.new(rest.outputs["Vector"], aov.inputs["Color"])
    return mat


def set_material(ob, mat):
    ob.data.materials.clear()
    ob.data.materials.append(mat)


def key_linear(ob):
    """Per-frame keys everywhere: make every F-curve linear so frame positions are exact."""
    ads = [ob.animation_data]
    if ob.type == "MESH" and ob.data.shape_keys is not None:
        ads.append(ob.data.shape_keys.animation_data)
    for ad in ads:
        if ad is None or ad.action is None:
            continue
        for fc in ad.action.fcurves:
            fc.extrapolation = "LINEAR"
            for kp in fc.keyframe_points:
                kp.interpolation = "LINEAR"


def look_at(cam, pos, target, roll=0.0):
    cam.location = pos
    d = Vector(target) - Vector(pos)
    q = d.to_track_quat("-Z", "Y")
    e = q.to_euler()
    if roll:
        e.rotate_axis("Z", roll)
    cam.rotation_euler = e


def add_camera(lens=35.0):
    cd = bpy.data.cameras.new("Camera")
    cd.lens = lens
    cd.sensor_width = 36.0
    cd.sensor_fit = "HORIZONTAL"
    cd.clip_start = 0.1
    cd.clip_end = 200.0
    cam = bpy.data.objects.new("Camera", cd)
    bpy.context.scene.collection.objects.link(cam)
    bpy.context.scene.camera = cam
    return cam


def add_lights(sun_rot=(math.radians(50), math.radians(10), math.radians(35)), sun_energy=3.5,
               world_col=(0.32, 0.40, 0.55), world_strength=0.8):
    """One hard sun with shadows; the world is seen by the camera only.  The fill light is an
    emission term in the materials (see make_material): no light selection between several
    lights, no image-based or indirect lighting, so the renders are nearly noise-free at low
    sample counts (cheap to render, and they compress well)."""
    ld = bpy.data.lights.new("Sun", "SUN")
    ld.energy = sun_energy
    ld.angle = 0.0                     # hard sun: no light-sampling noise
    ld.color = (1.0, 0.95, 0.88)
    sun = bpy.data.objects.new("Sun", ld)
    sun.rotation_euler = sun_rot
    bpy.context.scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (*world_col, 1.0)
    bg.inputs["Strength"].default_value = world_strength
    vis = world.cycles_visibility
    vis.diffuse = vis.glossy = vis.transmission = vis.scatter = False
    bpy.context.scene.world = world


# --------------------------------------------------------------------------------------------
# render settings


def setup_render(sc, args, shot):
    w, h = (int(v) for v in args.res.lower().split("x"))
    r = sc.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.fps = 24
    r.use_motion_blur = False          # the Vector pass is only written without motion blur
    r.film_transparent = False
    r.threads_mode = "FIXED"
    r.threads = args.threads
    r.use_persistent_data = False
    r.use_file_extension = True
    r.use_overwrite = True
    r.use_placeholder = False
    r.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    r.image_settings.color_depth = "16"   # half float
    r.image_settings.exr_codec = "ZIP"
    r.use_stamp = False
    r.filepath = os.path.join(os.path.abspath(args.out), shot, shot + ".####")
    sc.frame_start, sc.frame_end = 1, args.frames
    if args.frame_range:
        a, b = (int(v) for v in args.frame_range.split("-"))
        sc.frame_start, sc.frame_end = a, b
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"

    c = sc.cycles
    c.device = "CPU"
    c.samples = args.samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = 1
    c.use_animated_seed = False
    c.max_bounces = 0                  # direct light only: no noise from surfaces lighting each other
    c.diffuse_bounces = 0
    c.glossy_bounces = 0
    c.transmission_bounces = 0
    c.volume_bounces = 0
    c.transparent_max_bounces = 2
    c.caustics_reflective = False
    c.caustics_refractive = False
    c.pixel_filter_type = "BLACKMAN_HARRIS"
    c.filter_width = 1.5
    c.use_auto_tile = True
    c.tile_size = 64

    vl = sc.view_layers[0]
    vl.name = "ViewLayer"
    vl.use_pass_combined = True
    vl.use_pass_z = True
    vl.use_pass_mist = False
    vl.use_pass_vector = True
    vl.use_pass_normal = True
    vl.use_pass_uv = True
    vl.use_pass_position = True
    vl.use_pass_object_index = True
    vl.use_pass_diffuse_color = True
    vl.use_pass_diffuse_direct = True
    vl.cycles.denoising_store_passes = False
    if "Pref" not in vl.aovs:
        aov = vl.aovs.add()
        aov.name = "Pref"
    vl.aovs["Pref"].type = "COLOR"


# --------------------------------------------------------------------------------------------
# shots.  Frames 1..N are rendered; animation is keyed on every frame 0..N+1 (linear), so the
# previous/next-frame motion at the first/last rendered frame is real motion, not a clamp.


def frames_keyed(args):
    return range(0, args.frames + 2)


def ground_and_backdrop(ground_index, backdrop_index=None, backdrop_y=7.0):
    g = add_mesh_object("Ground", bm_grid(40.0, 40.0, 4, 4), ground_index)
    set_material(g, make_material("GroundMat", (0.62, 0.58, 0.50), (0.36, 0.34, 0.30), 0.5,
                                  noise_scale=0.3, roughness=0.8, specular=0.0))
    objs = [g]
    if backdrop_index is not None:
        b = add_mesh_object("Backdrop", bm_grid(30.0, 12.0, 4, 2), backdrop_index,
                            location=(0, backdrop_y, 5.5))
        b.rotation_euler = (math.radians(90), 0, 0)
        set_material(b, make_material("BackdropMat", (0.55, 0.62, 0.70), (0.40, 0.46, 0.55),
                                      0.6, noise_scale=0.25, roughness=0.9, specular=0.0))
        objs.append(b)
    return objs


def shot_crossing(sc, args):
    """Cube (1) sweeps left->right in front, accelerating; sphere (2) right->left behind it;
    torus (3) rises (accelerating) between them; ground (4), backdrop (5). Camera still."""
    n = args.frames
    cube = add_mesh_object("Cube", bm_cube(1.6), 1)
    set_material(cube, make_material("CubeMat", (0.85, 0.25, 0.15), (0.95, 0.80, 0.30), 1.2))
    sph = add_mesh_object("Sphere", bm_sphere(1.1), 2, smooth=True)
    set_material(sph, make_material("SphereMat", (0.15, 0.45, 0.85), (0.85, 0.90, 0.95), 1.5))
    tor = add_mesh_object("Torus", bm_torus(0.8, 0.3), 3, smooth=True)
    set_material(tor, make_material("TorusMat", (0.20, 0.70, 0.30), (0.90, 0.90, 0.60), 2.0))
    objs = [cube, sph, tor] + ground_and_backdrop(4, 5)
    cam = add_camera(35.0)
    add_lights()
    for f in frames_keyed(args):
        t = (f - 1) / (n - 1)                        # 0..1 over the rendered frames
        cube.location = (-5.5 + 11.0 * t * t, -1.5, 0.8)          # accelerating to the right
        cube.rotation_euler = (0, 0, math.radians(10 + 60 * t))
        sph.location = (4.5 - 9.0 * t, 1.5, 1.1 + 0.15 * math.sin(2 * math.pi * t))
        tor.location = (1.2, 0.2, 0.4 + 3.0 * t * t)               # accelerating upwards
        tor.rotation_euler = (math.radians(70), 0, 0)
        for ob in (cube, sph, tor):
            ob.keyframe_insert("location", frame=f)
            ob.keyframe_insert("rotation_euler", frame=f)
        look_at(cam, (0.0, -12.0, 2.6), (0.0, 0.0, 1.3))     # still camera
    for ob in (cube, sph, tor):
        key_linear(ob)
    return objs, cam


def shot_dolly(sc, args):
    """Camera dollies from 16 to 4 units from the centre pillar (4x scale change).
    Pillar (1), ball on top of a block (2, 3), ground (4); sky is visible above the horizon."""
    n = args.frames
    pil = add_mesh_object("Pillar", bm_cylinder(0.6, 3.0, 32, cuts=6), 1, location=(0, 0, 1.5),
                          smooth=True)
    set_material(pil, make_material("PillarMat", (0.80, 0.75, 0.65), (0.45, 0.30, 0.25), 1.6))
    ball = add_mesh_object("Ball", bm_sphere(0.7), 2, location=(-1.8, 1.0, 2.2), smooth=True)
    set_material(ball, make_material("BallMat", (0.90, 0.55, 0.10), (0.25, 0.20, 0.60), 2.2))
    blk = add_mesh_object("Block", bm_cube(1.5), 3, location=(-1.8, 1.0, 0.75))
    blk.rotation_euler = (0, 0, math.radians(30))
    set_material(blk, make_material("BlockMat", (0.30, 0.65, 0.70), (0.90, 0.95, 0.85), 1.3))
    cub = add_mesh_object("Crate", bm_cube(1.0), 4, location=(1.9, -0.5, 0.5))
    cub.rotation_euler = (0, 0, math.radians(-20))
    set_material(cub, make_material("CrateMat", (0.55, 0.80, 0.25), (0.20, 0.35, 0.15), 1.8))
    objs = [pil, ball, blk, cub] + ground_and_backdrop(5, None)
    cam = add_camera(35.0)
    add_lights(sun_rot=(math.radians(55), 0, math.radians(-30)))
    target = Vector((0.0, 0.0, 1.7))
    for f in frames_keyed(args):
        t = (f - 1) / (n - 1)
        dist = 16.0 - 12.0 * t                      # 16 -> 4 units: 4x scale on the pillar
        pos = target + Vector((0.25 * dist * 0.2, -dist, 0.25 + 0.04 * dist))
        look_at(cam, pos, target + Vector((0, 0, 0.6)))
        cam.keyframe_insert("location", frame=f)
        cam.keyframe_insert("rotation_euler", frame=f)
    key_linear(cam)
    return objs, cam


def shot_deform(sc, args):
    """Cloth sheet with a travelling Wave modifier (1), ball with an animated squash/stretch shape
    key (2), bar twisted by an animated Simple Deform modifier (3), ground (4), backdrop (5).
    Camera still. Pref (rest position) stays on the surface while P moves."""
    n = args.frames
    sheet = add_mesh_object("Sheet", bm_grid(4.5, 3.5, 60, 48), 1, location=(-1.3, 0.5, 0.6))
    sheet.rotation_euler = (0, 0, math.radians(8))
    for p in sheet.data.polygons:
        p.use_smooth = True
    set_material(sheet, make_material("SheetMat", (0.85, 0.85, 0.80), (0.70, 0.15, 0.20), 2.0))
    wave = sheet.modifiers.new("Wave", "WAVE")
    wave.use_x, wave.use_y = True, False          # straight crests travelling along local x
    wave.height = 0.4
    wave.width = 1.4
    wave.narrowness = 1.2
    wave.speed = 0.15
    wave.time_offset = -200.0                     # fully developed from frame 0
    wave.start_position_x = -3.0
    wave.use_normal = False

    ball = add_mesh_object("Ball", bm_sphere(0.8, 48, 24), 2, location=(2.2, -0.2, 0.8),
                           smooth=True)
    set_material(ball, make_material("BallMat", (0.20, 0.45, 0.85), (0.95, 0.85, 0.30), 2.5))
    ball.shape_key_add(name="Basis", from_mix=False)
    sk = ball.shape_key_add(name="Stretch", from_mix=False)
    for v in sk.data:
        x, y, z = v.co
        # stretch up and thin out, keeping the bottom on the ground (z = -0.8)
        v.co = (x * 0.72, y * 0.72, (z + 0.8) * 1.9 - 0.8)

    bar = add_mesh_object("Bar", bm_cylinder(0.5, 2.6, 4, cuts=24), 3, location=(-2.9, 3.0, 1.3))
    bar.rotation_euler = (0, 0, math.radians(45))
    set_material(bar, make_material("BarMat", (0.25, 0.70, 0.35), (0.95, 0.95, 0.90), 3.0))
    twist = bar.modifiers.new("Twist", "SIMPLE_DEFORM")
    twist.deform_method = "TWIST"
    twist.deform_axis = "Z"

    objs = [sheet, ball, bar] + ground_and_backdrop(4, 5, backdrop_y=5.0)
    cam = add_camera(35.0)
    add_lights(sun_rot=(math.radians(45), math.radians(5), math.radians(30)))
    look_at(cam, (0.3, -9.0, 4.6), (0.3, 0.6, 0.8))
    for f in frames_keyed(args):
        t = (f - 1) / (n - 1)
        sk.value = 0.5 - 0.5 * math.cos(2 * math.pi * t)            # 0 -> 1 -> 0
        ball.data.shape_keys.key_blocks["Stretch"].keyframe_insert("value", frame=f)
        twist.angle = math.radians(-90 + 270 * t)
        bar.keyframe_insert('modifiers["Twist"].angle', frame=f)
    key_linear(ball)
    key_linear(bar)
    return objs, cam


def to_half(sc, args, shot):
    """Blender writes data passes (Depth, Vector, Normal, Position, UV, IndexOB) as float32 even
    when half is asked for; convert every channel to half (ZIP) with oiiotool, which keeps the
    channel names.  Depth's 1e10 background becomes +inf in half."""
    import shutil
    import subprocess
    tool = shutil.which("oiiotool")
    if tool is None:
        print("make_plates: oiiotool not found, leaving Blender's mixed half/float EXRs")
        return
    for f in range(sc.frame_start, sc.frame_end + 1):
        path = bpy.path.abspath(sc.render.frame_path(frame=f))
        tmp = path + ".tmp.exr"
        # drop the attributes that change from run to run (dates, timings, the command line
        # with absolute paths) and pin the DateTime that oiiotool always writes, so that
        # regenerated plates are byte-identical
        subprocess.run([tool, "--nosoftwareattrib", path,
                        "--eraseattrib", "Date", "--eraseattrib", "RenderTime",
                        "--eraseattrib", "cycles.*time",
                        "--attrib", "DateTime", "2000:01:01 00:00:00",
                        "-d", "half", "--compression", "zip", "-o", tmp], check=True)
        os.replace(tmp, path)


SHOTS = {"crossing": shot_crossing, "dolly": shot_dolly, "deform": shot_deform}


# --------------------------------------------------------------------------------------------
# metadata: camera and object matrices per frame (ground truth for measurement/tests)


def mat_list(m):
    return [[round(v, 7) for v in row] for row in m]


def write_metadata(sc, args, shot, objs, cam):
    w, h = sc.render.resolution_x, sc.render.resolution_y
    meta = {
        "shot": shot,
        "generator": "samples/blender/make_plates.py",
        "blender": bpy.app.version_string,
        "resolution": [w, h],
        "frames": [1, args.frames],
        "fps": sc.render.fps,
        "samples": args.samples,
        "pixel_filter": {"type": "BLACKMAN_HARRIS", "width_px": sc.cycles.filter_width},
        "camera": {"lens_mm": cam.data.lens, "sensor_width_mm": cam.data.sensor_width,
                   "sensor_fit": cam.data.sensor_fit,
                   "focal_px": cam.data.lens / cam.data.sensor_width * w,
                   "note": "Blender camera looks down its local -Z, +Y up. Pixel (col,row), rows "
                           "top-down, centre at +0.5: col = w/2 + focal_px*x/(-z), "
                           "row = h/2 - focal_px*y/(-z) for camera-space (x,y,z)."},
        "objects": {ob.name: {"pass_index": ob.pass_index} for ob in objs},
        "per_frame": {},
    }
    for f in frames_keyed(args):
        sc.frame_set(f)
        meta["per_frame"][str(f)] = {
            "camera_matrix_world": mat_list(cam.matrix_world),
            "objects": {ob.name: mat_list(ob.matrix_world) for ob in objs},
        }
    sc.frame_set(1)
    d = os.path.join(os.path.abspath(args.out), shot)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, shot + ".json"), "w") as fp:
        json.dump(meta, fp, indent=1)


# --------------------------------------------------------------------------------------------


def main():
    args = parse_args()
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "LINEAR"
    sc = bpy.context.scene
    total0 = time.time()
    for shot in [s for s in args.shots.split(",") if s]:
        clear_scene()
        setup_render(sc, args, shot)
        objs, cam = SHOTS[shot](sc, args)
        write_metadata(sc, args, shot, objs, cam)
        t0 = time.time()
        bpy.ops.render.render(animation=True)
        print("make_plates: %s frames %d-%d rendered in %.1f s"
              % (shot, sc.frame_start, sc.frame_end, time.time() - t0), flush=True)
        if not args.keep_float:
            to_half(sc, args, shot)
    print("make_plates: all done in %.1f s" % (time.time() - total0), flush=True)


if __name__ == "__main__":
    main()
