"""sora sky: a Blender add-on (extension) that lights a scene with sora's
spectral sky: a World panel, one operator ("Update") and their settings.

The computing is in :mod:`.core` (no Blender) and :mod:`.world` (Blender
data); this module holds the interface only. Units and conventions:
:mod:`.core` and README "Blender".
"""

import bpy

from . import core

_SUN_FROM = [
    ("angles", "Elevation and azimuth", "The sun's elevation and azimuth, degrees"),
    ("time", "Date, time and place", "The sun at an instant (RFC 3339 with a zone) from a place"),
]
_SUN_AS = [
    ("lamp", "Sun lamp", "A Sun lamp with sora's direct normal irradiance and colour; the disc left out of the map"),
    ("disc", "Disc in the map", "The sun's disc drawn energy-true in the map; no lamp"),
]
_POLARISATION = [
    ("scalar", "Scalar", "Scalar light (the library's default)"),
    ("vector", "Vector", "Stokes vectors through every scattering; the radiance is their intensity"),
]


# The library's presets (static items, so that the default can be named).
_PRESETS = [(name, name, "A built-in atmosphere of sora") for name in core.sora.Atmosphere.presets()]


class SoraSkyProperties(bpy.types.PropertyGroup):
    preset: bpy.props.EnumProperty(name="Preset", items=_PRESETS, default="earth-clear")
    atmosphere_path: bpy.props.StringProperty(
        name="Atmosphere file", subtype="FILE_PATH",
        description="An atmosphere file (TOML); empty: the preset",
    )
    override_aerosol: bpy.props.BoolProperty(name="Aerosol optical depth", default=False)
    aerosol_optical_depth: bpy.props.FloatProperty(
        name="Optical depth (550 nm)", default=0.1, min=0.0, soft_max=3.0, precision=3
    )
    override_ozone: bpy.props.BoolProperty(name="Ozone", default=False)
    ozone_dobson_units: bpy.props.FloatProperty(name="Ozone (DU)", default=300.0, min=0.0, soft_max=600.0)
    override_albedo: bpy.props.BoolProperty(name="Ground albedo", default=False)
    ground_albedo: bpy.props.FloatProperty(name="Albedo", default=0.1, min=0.0, max=1.0)
    sun_from: bpy.props.EnumProperty(name="Sun", items=_SUN_FROM, default="angles")
    sun_elevation_deg: bpy.props.FloatProperty(name="Elevation (deg)", default=30.0, min=-90.0, max=90.0)
    sun_azimuth_deg: bpy.props.FloatProperty(
        name="Azimuth (deg)", default=180.0, min=0.0, max=360.0,
        description="Clockwise from north (+Y): 90 east (+X)",
    )
    time: bpy.props.StringProperty(
        name="Time", default="2026-06-21T19:00:00+09:00",
        description="RFC 3339 with Z or a zone offset, e.g. 2026-06-21T19:00:00+09:00",
    )
    latitude_deg: bpy.props.FloatProperty(name="Latitude (deg N)", default=35.68, min=-90.0, max=90.0)
    longitude_deg: bpy.props.FloatProperty(name="Longitude (deg E)", default=139.77, min=-180.0, max=180.0)
    site_elevation_m: bpy.props.FloatProperty(name="Site elevation (m)", default=0.0)
    observer_altitude_m: bpy.props.FloatProperty(name="Eye altitude (m)", default=0.0, min=0.0)
    polarisation: bpy.props.EnumProperty(name="Polarisation", items=_POLARISATION, default="scalar")
    sun_as: bpy.props.EnumProperty(name="Sun as", items=_SUN_AS, default="lamp")
    map_width: bpy.props.IntProperty(name="Map width (px)", default=1024, min=64, max=8192, step=4)
    use_haze: bpy.props.BoolProperty(name="Haze", default=False)
    haze_size_m: bpy.props.FloatProperty(name="Haze across (m)", default=2000.0, min=1.0)
    haze_height_m: bpy.props.FloatProperty(name="Haze height (m)", default=100.0, min=0.1)

    def settings(self) -> core.SkySettings:
        """The panel as :class:`core.SkySettings`."""
        return core.SkySettings(
            preset=self.preset,
            atmosphere_path=bpy.path.abspath(self.atmosphere_path) if self.atmosphere_path else "",
            aerosol_optical_depth=self.aerosol_optical_depth if self.override_aerosol else None,
            ozone_dobson_units=self.ozone_dobson_units if self.override_ozone else None,
            ground_albedo=self.ground_albedo if self.override_albedo else None,
            sun_from=self.sun_from,
            sun_elevation_deg=self.sun_elevation_deg,
            sun_azimuth_deg=self.sun_azimuth_deg,
            time=self.time,
            latitude_deg=self.latitude_deg,
            longitude_deg=self.longitude_deg,
            site_elevation_m=self.site_elevation_m,
            observer_altitude_m=self.observer_altitude_m,
            polarisation=self.polarisation,
            map_width=self.map_width - self.map_width % 4,
            sun_as=self.sun_as,
        )


class SORA_OT_update_world(bpy.types.Operator):
    """Make the world from sora's sky (map, sun, haze)"""

    bl_idname = "sora.update_world"
    bl_label = "Update"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        from . import world

        properties = context.scene.sora_sky
        try:
            summary = world.update_world(
                context.scene,
                properties.settings(),
                properties.haze_size_m if properties.use_haze else None,
                properties.haze_height_m,
            )
        except (ValueError, OSError) as error:
            # The library's one line; the previous world stays.
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report(
            {"INFO"},
            "sora: sun {sun_elevation_deg:.2f} deg at azimuth {sun_azimuth_deg:.2f} deg, "
            "direct normal {direct_normal_w_m2:.1f} W m^-2; map {map}".format(**summary),
        )
        return {"FINISHED"}


class SORA_PT_world(bpy.types.Panel):
    bl_label = "sora sky"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"

    def draw(self, context):
        properties = context.scene.sora_sky
        layout = self.layout
        layout.use_property_split = True
        layout.prop(properties, "preset")
        layout.prop(properties, "atmosphere_path")
        for flag, value in (
            ("override_aerosol", "aerosol_optical_depth"),
            ("override_ozone", "ozone_dobson_units"),
            ("override_albedo", "ground_albedo"),
        ):
            row = layout.row(heading=properties.bl_rna.properties[flag].name)
            row.prop(properties, flag, text="")
            sub = row.row()
            sub.active = getattr(properties, flag)
            sub.prop(properties, value, text="")
        layout.prop(properties, "sun_from")
        if properties.sun_from == "angles":
            layout.prop(properties, "sun_elevation_deg")
            layout.prop(properties, "sun_azimuth_deg")
        else:
            layout.prop(properties, "time")
            layout.prop(properties, "latitude_deg")
            layout.prop(properties, "longitude_deg")
            layout.prop(properties, "site_elevation_m")
        layout.prop(properties, "observer_altitude_m")
        layout.prop(properties, "polarisation")
        layout.prop(properties, "sun_as")
        layout.prop(properties, "map_width")
        row = layout.row(heading="Haze")
        row.prop(properties, "use_haze", text="")
        sub = row.row()
        sub.active = properties.use_haze
        sub.prop(properties, "haze_size_m", text="")
        sub.prop(properties, "haze_height_m", text="")
        layout.operator(SORA_OT_update_world.bl_idname)


_CLASSES = (SoraSkyProperties, SORA_OT_update_world, SORA_PT_world)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.sora_sky = bpy.props.PointerProperty(type=SoraSkyProperties)


def unregister():
    del bpy.types.Scene.sora_sky
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
