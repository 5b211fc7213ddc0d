"""Validates the WGSL reference shader (web/shaders/sora_sky.wgsl) with
wgpu-native's WGSL front end (naga, through the `wgpu` package pinned in
requirements-wgsl.txt): the module must parse and type-check, and a render
pipeline whose fragment stage calls every public function must build, on
whatever adapter the machine has (Mesa's llvmpipe on a machine without a
GPU). Nothing is drawn: the GLSL twin is the one the browser test draws.

Run: python web/tests/validate_wgsl.py web/shaders/sora_sky.wgsl
"""
import sys, wgpu
source = open(sys.argv[1]).read()
# An entry point that calls every public function, so that each is
# type-checked in a pipeline too.
source += """
@fragment
fn sora_check_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
  let v = normalize(vec3<f32>(position.x, position.y, 1.0));
  let sun = normalize(vec3<f32>(0.0, -1.0, 0.2));
  let a = sora_aerial_perspective(10.0, v, sun, 1000.0);
  let b = sora_aerial_perspective_from_sky(10.0, v, sun, 1000.0);
  let m = sora_aerial_perspective_march(10.0, v, sun, 1000.0);
  let c = sora_sky_view(10.0, v, sun) + sora_sun_disc_xyz(0.0, 5.0, 0.001)
    + sora_ground_irradiance_xyz(0.0, 5.0) + a.inscattered * a.transmittance
    + b.inscattered * b.transmittance + m.inscattered * m.transmittance
    + sora_raised_sky_xyz(5000.0, 1.2, 0.5, 10.0) + sora_raised_sky_view(5000.0, v, sun);
  return vec4<f32>(sora_xyz_to_linear_srgb(c), 1.0);
}
@vertex
fn sora_check_vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
  return vec4<f32>(f32(i), 0.0, 0.0, 1.0);
}
"""
adapter = wgpu.gpu.request_adapter_sync(power_preference="low-power")
device = adapter.request_device_sync()
module = device.create_shader_module(code=source)
pipeline = device.create_render_pipeline(
    layout="auto",
    vertex={"module": module, "entry_point": "sora_check_vertex"},
    fragment={"module": module, "entry_point": "sora_check_main",
              "targets": [{"format": wgpu.TextureFormat.rgba8unorm}]},
    primitive={"topology": wgpu.PrimitiveTopology.triangle_list},
)
print("WGSL valid:", sys.argv[1], "pipeline built on", adapter.info["device"])
