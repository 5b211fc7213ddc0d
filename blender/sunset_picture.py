"""docs/blender_sunset.png: one scene at sunset over Tokyo (2026-06-21 18:50 JST), lit by the
add-on's world (left) and by Blender's own Sky Texture (right, its
multiple-scattering model, with the same sun), rendered by Cycles.

    target/blender-venv/bin/python blender/sunset_picture.py [docs/blender_sunset.png]

(a venv with bpy and sora: README "Blender"; about a minute on 2 cores).
Each half is exposed on its own (its median luminance to 0.18, then
x / (1 + x) and the sRGB curve): the two skies have different absolute
scales (sora's is W m^-2 sr^-1; the printed ratio says by how much the
Sky Texture's median differs).
"""

import math
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sora_sky import core, world  # noqa: E402

TIME = "2026-06-21T18:50:00+09:00"
PLACE = (35.68, 139.77, 40.0)
WIDTH, HEIGHT, SAMPLES = 384, 216, 32


def build_scene(view_azimuth_deg):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_denoising = True
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"

    def material(name, albedo):
        m = bpy.data.materials.new(name)
        m.use_nodes = True
        principled = m.node_tree.nodes["Principled BSDF"]
        principled.inputs["Base Color"].default_value = (*albedo, 1.0)
        principled.inputs["Roughness"].default_value = 0.6
        return m

    bpy.ops.mesh.primitive_plane_add(size=400.0)
    bpy.context.object.data.materials.append(material("ground", (0.12, 0.12, 0.11)))
    # A row of white spheres and a red cube in front of the camera.
    ahead = core.sun_direction(0.0, view_azimuth_deg)
    across = np.array([ahead[1], -ahead[0], 0.0])
    for k in range(5):
        where = ahead * (9.0 + 3.0 * k) + across * (-5.0 + 2.5 * k)
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.8, location=(where[0], where[1], 0.8))
        bpy.ops.object.shade_smooth()
        bpy.context.object.data.materials.append(material(f"sphere{k}", (0.8, 0.8, 0.8)))
    where = ahead * 8.0 + across * -4.0
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(where[0], where[1], 1.0))
    bpy.context.object.data.materials.append(material("cube", (0.7, 0.25, 0.2)))
    return scene


def aim_camera(scene, azimuth_deg, pitch_deg):
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.location = (0.0, 0.0, 1.7)
    camera.data.lens = 24.0
    look = Vector(core.sun_direction(pitch_deg, azimuth_deg))
    camera.rotation_mode = "QUATERNION"
    camera.rotation_quaternion = (-look).to_track_quat("Z", "Y")
    scene.camera = camera


def tone_map(linear):
    luminance = linear @ core.LUMINANCE_WEIGHTS
    exposed = linear * (0.18 / max(np.median(luminance), 1e-30))
    mapped = exposed / (1.0 + exposed)
    return np.where(mapped <= 0.0031308, 12.92 * mapped, 1.055 * mapped ** (1 / 2.4) - 0.055)


def main(output):
    # The sun's disc drawn in the map (energy-true), so that it shows, as
    # the Sky Texture's does; a Sun lamp is not seen by camera rays.
    settings = core.SkySettings(sun_from="time", time=TIME, latitude_deg=PLACE[0],
                                longitude_deg=PLACE[1], site_elevation_m=PLACE[2], map_width=2048,
                                sun_as="disc")
    sky, _ = core.make_sky(settings)
    elevation, azimuth = sky.sun_position_deg
    scene = build_scene(azimuth - 20.0)
    world.update_world(scene, settings)
    print(f"sun {elevation:.2f} deg at azimuth {azimuth:.2f} deg ({TIME}, {PLACE})")
    aim_camera(scene, azimuth - 20.0, 4.0)
    sora_image = world.render_linear(scene)

    # Blender's Sky Texture, the same sun (its rotation: azimuth from +Y,
    # clockwise, as the add-on's), its own disc; no lamp.
    sky_world = bpy.data.worlds.new("Blender sky")
    sky_world.use_nodes = True
    tree = sky_world.node_tree
    texture = tree.nodes.new("ShaderNodeTexSky")
    texture.sky_type = "MULTIPLE_SCATTERING" if "MULTIPLE_SCATTERING" in {
        item.identifier for item in texture.bl_rna.properties["sky_type"].enum_items} else "NISHITA"
    texture.sun_elevation = math.radians(elevation)
    texture.sun_rotation = math.radians(azimuth)
    texture.altitude = PLACE[2]
    tree.links.new(texture.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    scene.world = sky_world
    blender_image = world.render_linear(scene)
    ratio = np.median(blender_image @ core.LUMINANCE_WEIGHTS) / np.median(sora_image @ core.LUMINANCE_WEIGHTS)
    print(f"median luminance, Sky Texture / sora: {ratio:.3g}")

    gap = np.ones((HEIGHT, 4, 3))
    side_by_side = np.concatenate([tone_map(sora_image), gap, tone_map(blender_image)], axis=1)
    height, width, _ = side_by_side.shape
    rgba = np.ones((height, width, 4), dtype=np.float32)
    rgba[..., :3] = np.clip(side_by_side, 0.0, 1.0)
    picture = bpy.data.images.new("side by side", width, height, alpha=False)
    picture.pixels.foreach_set(rgba.ravel())
    partial = output + ".partial.png"
    picture.filepath_raw = partial
    picture.file_format = "PNG"
    picture.save()
    os.replace(partial, output)
    print(f"wrote {output}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/blender_sunset.png")
