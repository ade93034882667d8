//! Texture sampling (src/texture, src/cpu/texture.rs, shaders/texture.wgsl):
//! hand-computed values of the CPU twin, and the shader's results equal to
//! it bit for bit.

mod common;

use glam::{Vec2, Vec3};
use lambert::cpu::texture::Textures;
use lambert::loading::material::{
    Filter, IDENTITY_UV_TRANSFORM, ImageSource, Sampler, TextureUse, Wrap,
};
use lambert::texture::{
    DecodedImage, LINEAR_ONE, TextureStore, decode_image, linear_from_srgb, mip_chain,
};

const WHITE: [u8; 4] = [255, 255, 255, 255];
const BLACK: [u8; 4] = [0, 0, 0, 255];

fn image(width: u32, height: u32, texels: &[[u8; 4]]) -> DecodedImage {
    DecodedImage {
        width,
        height,
        rgba: texels.concat(),
        format: "PNG",
    }
}

fn sampler(wrap: Wrap, filter: Filter) -> Sampler {
    Sampler {
        wrap_u: wrap,
        wrap_v: wrap,
        magnify: filter,
        minify: filter,
        mipmaps: true,
    }
}

fn texture_use(sampler: Sampler) -> TextureUse {
    TextureUse {
        image: 0,
        sampler,
        transform: IDENTITY_UV_TRANSFORM,
    }
}

/// The store of `image` alone with one slot of `sampler`.
fn store(image: DecodedImage, sampler: Sampler) -> (TextureStore, u32) {
    let mut store = TextureStore::default();
    let index = store.add_image(&image, "test".into());
    let slot = store.slot(index, &texture_use(sampler));
    (store, slot)
}

fn red_at(store: &TextureStore, slot: u32, u: f32, v: f32, lod: i32) -> f32 {
    Textures {
        words: store.words(),
    }
    .sample_texture(slot, Vec2::new(u, v), lod)
    .x
}

#[test]
fn srgb_bytes_decode_to_linear_light() {
    assert_eq!(linear_from_srgb(0), 0);
    assert_eq!(linear_from_srgb(255), LINEAR_ONE);
    // 10/255 is on the linear segment: 0.0392157 / 12.92 · 32768 = 99.46.
    assert_eq!(linear_from_srgb(10), 99);
    // ((128/255 + 0.055) / 1.055)^2.4 = 0.2158605 · 32768 = 7073.3.
    assert_eq!(linear_from_srgb(128), 7073);
    // Through a sample: a 1×1 texture of sRGB 128 (alpha 51: linear 0.2).
    let (s, slot) = store(
        image(1, 1, &[[128, 10, 255, 51]]),
        sampler(Wrap::Repeat, Filter::Linear),
    );
    let c = Textures { words: s.words() }.sample_texture(slot, Vec2::new(0.3, 0.9), 0);
    assert_eq!(c.x, 7073.0 / 32768.0);
    assert_eq!(c.y, 99.0 / 32768.0);
    assert_eq!(c.z, 1.0);
    // Alpha is linear: 51 / 255 = 0.2, in 1/32768 rounded: 6554.
    assert_eq!(c.w, 6554.0 / 32768.0);
}

#[test]
fn bilinear_weights_are_hand_computed_between_texel_centres() {
    // White then black; texel centres at u = 0.25 and 0.75.
    let (s, slot) = store(
        image(2, 1, &[WHITE, BLACK]),
        sampler(Wrap::ClampToEdge, Filter::Linear),
    );
    assert_eq!(red_at(&s, slot, 0.25, 0.5, 0), 1.0);
    assert_eq!(red_at(&s, slot, 0.75, 0.5, 0), 0.0);
    assert_eq!(red_at(&s, slot, 0.5, 0.5, 0), 0.5);
    // A quarter of the way from the white centre to the black: 3/4 white.
    assert_eq!(red_at(&s, slot, 0.375, 0.5, 0), 0.75);
    // Nearest: the texel the point is in.
    let (s, slot) = store(
        image(2, 1, &[WHITE, BLACK]),
        sampler(Wrap::ClampToEdge, Filter::Nearest),
    );
    assert_eq!(red_at(&s, slot, 0.49, 0.5, 0), 1.0);
    assert_eq!(red_at(&s, slot, 0.51, 0.5, 0), 0.0);
}

#[test]
fn each_wrap_mode_reads_outside_the_image_as_gltf_says() {
    let sample = |wrap, u| {
        let (s, slot) = store(image(2, 1, &[WHITE, BLACK]), sampler(wrap, Filter::Linear));
        red_at(&s, slot, u, 0.5, 0)
    };
    // At u = 0 the left neighbour is the last texel (repeat), the first
    // itself (mirror, clamp).
    assert_eq!(sample(Wrap::Repeat, 0.0), 0.5);
    assert_eq!(sample(Wrap::MirroredRepeat, 0.0), 1.0);
    assert_eq!(sample(Wrap::ClampToEdge, 0.0), 1.0);
    // u = −0.25: repeat reads u = 0.75 (black), mirror u = 0.25 (white),
    // clamp the edge texel (white); u = 1.75: repeat 0.75, mirror 0.25.
    assert_eq!(sample(Wrap::Repeat, -0.25), 0.0);
    assert_eq!(sample(Wrap::MirroredRepeat, -0.25), 1.0);
    assert_eq!(sample(Wrap::ClampToEdge, -0.25), 1.0);
    assert_eq!(sample(Wrap::Repeat, 1.75), 0.0);
    assert_eq!(sample(Wrap::MirroredRepeat, 1.75), 1.0);
    assert_eq!(sample(Wrap::ClampToEdge, 1.75), 0.0);
    // Far from the image, and not a number: read as defined, no panic.
    assert_eq!(sample(Wrap::Repeat, 1000.25), 1.0);
    assert_eq!(sample(Wrap::Repeat, f32::NAN), 0.5);
}

#[test]
fn the_uv_transform_applies_before_wrapping() {
    let (mut s, _) = store(
        image(2, 1, &[WHITE, BLACK]),
        sampler(Wrap::Repeat, Filter::Nearest),
    );
    // u' = 0.5·u + 0.5: u = 0.2 reads 0.6 (black), not 0.2 (white).
    let slot = s.slot(
        0,
        &TextureUse {
            transform: [[0.5, 0.0, 0.5], [0.0, 1.0, 0.0]],
            ..texture_use(sampler(Wrap::Repeat, Filter::Nearest))
        },
    );
    assert_eq!(red_at(&s, slot, 0.2, 0.5, 0), 0.0);
}

#[test]
fn mip_levels_of_a_checker_average_in_linear_light() {
    let checker: Vec<[u8; 4]> = (0..16)
        .map(|i| {
            if (i % 4 + i / 4) % 2 == 0 {
                WHITE
            } else {
                BLACK
            }
        })
        .collect();
    let chain = mip_chain(4, 4, &checker.concat());
    let sizes: Vec<(u32, u32)> = chain.iter().map(|&(w, h, _)| (w, h)).collect();
    assert_eq!(sizes, [(4, 4), (2, 2), (1, 1)]);
    // Half white, half black: linear 0.5, whose nearest sRGB byte is 188
    // (sRGB(0.5) = 0.7354 · 255 = 187.5; 188 decodes to 0.5029, 187 to
    // 0.4969), not 128, the byte average.
    for level in &chain[1..] {
        assert!(level.2.iter().all(|&t| t == 0xff_bc_bc_bc), "{level:?}");
    }
    // Sampled at level 1 and between levels: 0.5029 either way, where the
    // base level alone at a texel centre gives 1.
    let (s, slot) = store(image(4, 4, &checker), sampler(Wrap::Repeat, Filter::Linear));
    let grey = linear_from_srgb(188) as f32 / 32768.0;
    assert_eq!(red_at(&s, slot, 0.125, 0.125, 0), 1.0);
    assert_eq!(red_at(&s, slot, 0.125, 0.125, 256), grey);
    assert_eq!(red_at(&s, slot, 0.125, 0.125, 2000), grey);
    // Half way from level 0 to 1 at a white centre: (1 + 0.5029) / 2.
    assert!((red_at(&s, slot, 0.125, 0.125, 128) - (1.0 + grey) / 2.0).abs() < 1e-4);
    // Odd sizes keep every texel: 3×1 → 1×1 averages all three.
    let odd = mip_chain(3, 1, &[WHITE, BLACK, BLACK].concat());
    assert_eq!(odd.len(), 2);
    assert_eq!(odd[1].2[0] & 255, 156); // linear 1/3 is sRGB byte 156
}

#[test]
fn ray_cone_lod_of_a_known_geometry() {
    let (s, slot) = store(
        image(256, 256, &vec![WHITE; 256 * 256]),
        sampler(Wrap::Repeat, Filter::Linear),
    );
    let t = Textures { words: s.words() };
    let (p0, p1, p2) = (Vec3::ZERO, Vec3::X, Vec3::Y);
    let (uv0, uv1, uv2) = (Vec2::ZERO, Vec2::X, Vec2::Y);
    let lod = |dir: Vec3, width: f32| t.texture_lod(slot, p0, p1, p2, uv0, uv1, uv2, dir, width);
    // 256 texels per unit; a cone 1/64 wide covers 4 texels: level 2.
    assert_eq!(lod(Vec3::Z, 1.0 / 64.0), 2 * 256);
    assert_eq!(lod(-Vec3::Z, 1.0 / 64.0), 2 * 256);
    // At 60° incidence the footprint is twice as long: one level more.
    assert_eq!(
        lod(Vec3::new(0.0, 0.75f32.sqrt(), 0.5), 1.0 / 64.0),
        3 * 256
    );
    // A cone of one texel: level 0; narrower: magnified.
    assert_eq!(lod(Vec3::Z, 1.0 / 256.0), 0);
    assert!(lod(Vec3::Z, 1.0 / 1024.0) < 0);
    // Between powers of two the level is the straight-line log2 of the
    // float's bits: 3 texels → 1 + 0.5 (log2 3 = 1.585).
    assert_eq!(lod(Vec3::Z, 3.0 / 256.0), 256 + 128);
    // A camera's cone: one pixel's angle (2·tan(vfov/2)/height), and at 16
    // samples a quarter of it, so the level is two lower: jittered samples
    // read finer levels and converge to the full texture's box filter.
    let spread = lambert::texture::cone_spread(1.0, 512, 1);
    assert_eq!(spread, 2.0 / 512.0);
    assert_eq!(lambert::texture::cone_spread(1.0, 512, 16), spread / 4.0);
    assert_eq!(
        lod(Vec3::Z, 64.0 * spread) - lod(Vec3::Z, 16.0 * spread),
        2 * 256
    );
}

#[test]
fn images_that_do_not_decode_say_which_and_why() {
    let dir = tempfile::tempdir().unwrap();
    // A PNG cut short.
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(8, 8, image::Rgba(WHITE))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let cut = ImageSource::Embedded {
        bytes: png[..png.len() / 2].to_vec(),
        name: "cut.glb image 0".into(),
    };
    let e = decode_image(&cut).unwrap_err();
    assert!(
        e.starts_with("cut.glb image 0: not a readable PNG image"),
        "{e}"
    );
    let whole = ImageSource::Embedded {
        bytes: png,
        name: "whole".into(),
    };
    assert_eq!(decode_image(&whole).unwrap().rgba, [WHITE; 64].concat());
    // Not an image format lambert reads.
    let gif = ImageSource::Embedded {
        bytes: b"GIF89a\x01\x00\x01\x00".to_vec(),
        name: "m.gltf image 1".into(),
    };
    let e = decode_image(&gif).unwrap_err();
    assert!(
        e.contains("m.gltf image 1: a Gif image (lambert reads PNG and JPEG)"),
        "{e}"
    );
    // A missing file names the path.
    let missing = dir.path().join("missing.png");
    let e = decode_image(&ImageSource::File(missing.clone())).unwrap_err();
    assert!(e.contains(&missing.display().to_string()), "{e}");
    // A JPEG file.
    let path = dir.path().join("grey.jpg");
    image::RgbImage::from_pixel(16, 8, image::Rgb([128, 128, 128]))
        .save(&path)
        .unwrap();
    let jpeg = decode_image(&ImageSource::File(path)).unwrap();
    assert_eq!((jpeg.width, jpeg.height, jpeg.format), (16, 8, "JPEG"));
    assert!(
        jpeg.rgba
            .chunks(4)
            .all(|p| p[0].abs_diff(128) <= 2 && p[3] == 255)
    );
}

/// What the GPU test runs: the texture stage with its one binding, and two
/// entry points over arrays of inputs.
const TWIN_SHADER: &str = r#"
@group(0) @binding(0) var<storage, read> textures: array<u32>;
// The kernel reads them from the scene's words (shaders/fetch.wgsl).
fn texture_word(i: u32) -> u32 { return textures[i]; }
struct Sample { slot: u32, lod: i32, u: f32, v: f32 }
struct Footprint { p0: vec4<f32>, p1: vec4<f32>, p2: vec4<f32>, dir: vec4<f32>, uv01: vec4<f32>, uv2_b: vec4<f32>, slot: vec4<u32> }
@group(0) @binding(1) var<storage, read> samples: array<Sample>;
@group(0) @binding(2) var<storage, read> footprints: array<Footprint>;
@group(0) @binding(3) var<storage, read_write> sampled: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> lods: array<vec4<u32>>;
// What `rounded` selects on (the kernel's uniform `params.zero`): 0, read
// from a buffer so that no compiler knows it.
struct Params { zero: u32 }
@group(0) @binding(5) var<storage, read> params: Params;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&samples) {
        let s = samples[id.x];
        sampled[id.x] = sample_texture(s.slot, vec2<f32>(s.u, s.v), s.lod);
    }
    if id.x < arrayLength(&footprints) {
        let f = footprints[id.x];
        let uv = interpolate_uv(f.uv01.xy, f.uv01.zw, f.uv2_b.xy, f.uv2_b.z, f.uv2_b.w);
        let lod = texture_lod(f.slot.x, f.p0.xyz, f.p1.xyz, f.p2.xyz, f.uv01.xy, f.uv01.zw,
            f.uv2_b.xy, f.dir.xyz, f.dir.w);
        lods[id.x] = vec4<u32>(bitcast<u32>(lod), bitcast<u32>(uv.x), bitcast<u32>(uv.y), 0u);
    }
}
"#;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Footprint {
    p: [[f32; 4]; 3],
    dir: [f32; 4],
    uv01: [f32; 4],
    uv2_b: [f32; 4],
    slot: [u32; 4],
}

/// Runs TWIN_SHADER on `store`'s words; returns its two outputs.
fn run_twin_shader(
    words: &[u32],
    samples: &[[u32; 4]],
    footprints: &[Footprint],
) -> (Vec<[f32; 4]>, Vec<[u32; 4]>) {
    use wgpu::util::DeviceExt;
    let gpu = common::open_gpu();
    let device = &gpu.device;
    let source = format!("{}\n{TWIN_SHADER}", include_str!("../shaders/texture.wgsl"));
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("texture twin"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("texture twin"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let input = |bytes: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let output = |size: u64| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    };
    let (sampled_bytes, lod_bytes) = (16 * samples.len() as u64, 16 * footprints.len() as u64);
    let buffers = [
        input(bytemuck::cast_slice(words)),
        input(bytemuck::cast_slice(samples)),
        input(bytemuck::cast_slice(footprints)),
        output(sampled_bytes),
        output(lod_bytes),
        input(bytemuck::bytes_of(&0u32)),
    ];
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: sampled_bytes + lod_bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(
            (samples.len().max(footprints.len()) as u32).div_ceil(64),
            1,
            1,
        );
    }
    encoder.copy_buffer_to_buffer(&buffers[3], 0, &readback, 0, sampled_bytes);
    encoder.copy_buffer_to_buffer(&buffers[4], 0, &readback, sampled_bytes, lod_bytes);
    gpu.queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let bytes = readback.get_mapped_range(..).unwrap().to_vec();
    let (a, b) = bytes.split_at(sampled_bytes as usize);
    (
        bytemuck::cast_slice(a).to_vec(),
        bytemuck::cast_slice(b).to_vec(),
    )
}

/// The shader's `sample_texture`, `texture_lod` and `interpolate_uv` give
/// the CPU twin's results bit for bit, on random inputs over every wrap
/// mode, both filters, with and without mips, and a UV transform.
#[test]
fn gpu_sampling_equals_the_twin_bit_for_bit() {
    let mut rng = lambert::probe::Rng(30);
    let (width, height) = (37, 23);
    let texels: Vec<[u8; 4]> = (0..width * height)
        .map(|_| std::array::from_fn(|_| (rng.unit() * 256.0) as u8))
        .collect();
    let mut store = TextureStore::default();
    store.add_image(&image(width, height, &texels), "random".into());
    let wraps = [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge];
    let mut slots = Vec::new();
    for (i, wrap_u) in wraps.into_iter().enumerate() {
        for wrap_v in wraps {
            for filter in [Filter::Linear, Filter::Nearest] {
                slots.push(store.slot(
                    0,
                    &TextureUse {
                        image: 0,
                        sampler: Sampler {
                            wrap_u,
                            wrap_v,
                            magnify: filter,
                            minify: filter,
                            mipmaps: i != 1,
                        },
                        transform: [[0.8, -0.6, 0.3], [0.6, 0.8, -0.1 * i as f32]],
                    },
                ));
            }
        }
    }
    let twin = Textures {
        words: store.words(),
    };
    let mut f = |lo: f64, hi: f64| (lo + (hi - lo) * rng.unit()) as f32;
    let samples: Vec<[u32; 4]> = (0..4096)
        .map(|i| {
            [
                slots[i % slots.len()],
                f(-300.0, 2500.0) as i32 as u32,
                f(-3.0, 3.0).to_bits(),
                f(-3.0, 3.0).to_bits(),
            ]
        })
        .collect();
    let footprints: Vec<Footprint> = (0..4096)
        .map(|i| {
            let mut p = || [f(-5.0, 5.0), f(-5.0, 5.0), f(-5.0, 5.0), 0.0];
            let p = [p(), p(), p()];
            let d = Vec3::new(f(-1.0, 1.0), f(-1.0, 1.0), f(-1.0, 1.0)).normalize();
            Footprint {
                p,
                dir: [d.x, d.y, d.z, f(0.0, 0.1)],
                uv01: [f(-2.0, 2.0), f(-2.0, 2.0), f(-2.0, 2.0), f(-2.0, 2.0)],
                uv2_b: [f(-2.0, 2.0), f(-2.0, 2.0), f(0.0, 0.5), f(0.0, 0.5)],
                slot: [slots[i % slots.len()], 0, 0, 0],
            }
        })
        .collect();
    let (gpu_sampled, gpu_lods) = run_twin_shader(store.words(), &samples, &footprints);
    for (s, gpu) in samples.iter().zip(&gpu_sampled) {
        let uv = Vec2::new(f32::from_bits(s[2]), f32::from_bits(s[3]));
        let cpu = twin.sample_texture(s[0], uv, s[1] as i32).to_array();
        assert_eq!(cpu.map(f32::to_bits), gpu.map(f32::to_bits), "sample {s:?}");
    }
    for (fp, gpu) in footprints.iter().zip(&gpu_lods) {
        let v3 = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
        let (uv0, uv1) = (
            Vec2::new(fp.uv01[0], fp.uv01[1]),
            Vec2::new(fp.uv01[2], fp.uv01[3]),
        );
        let uv2 = Vec2::new(fp.uv2_b[0], fp.uv2_b[1]);
        let lod = twin.texture_lod(
            fp.slot[0],
            v3(fp.p[0]),
            v3(fp.p[1]),
            v3(fp.p[2]),
            uv0,
            uv1,
            uv2,
            v3(fp.dir),
            fp.dir[3],
        );
        let uv = lambert::cpu::texture::interpolate_uv(uv0, uv1, uv2, fp.uv2_b[2], fp.uv2_b[3]);
        assert_eq!(
            [lod as u32, uv.x.to_bits(), uv.y.to_bits()],
            gpu[..3],
            "footprint {:?}",
            bytemuck::cast::<Footprint, [f32; 28]>(*fp)
        );
    }
}

/// A model's images: one decoded once for all its users; one missing, one
/// not an image, one cut short: warnings that name the model, the image
/// and the materials, which keep their factors (no slot).
#[test]
fn model_textures_warn_for_images_that_do_not_decode() {
    use lambert::loading::material::MaterialDesc;
    use lambert::texture::{add_model_textures, describe_images};
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("grid.png");
    image::RgbaImage::from_pixel(4, 2, image::Rgba([10, 20, 30, 255]))
        .save(&good)
        .unwrap();
    let png = std::fs::read(&good).unwrap();
    let images = [
        ImageSource::File(good.clone()),
        ImageSource::File(dir.path().join("missing.png")),
        ImageSource::Embedded {
            bytes: b"<html>not found</html>".to_vec(),
            name: "model.gltf image 2 (data URI)".into(),
        },
        ImageSource::Embedded {
            bytes: png[..png.len() - 20].to_vec(),
            name: "model.gltf image 3".into(),
        },
    ];
    let uses = |image| {
        Some(TextureUse {
            image,
            ..texture_use(Sampler::default())
        })
    };
    let materials: Vec<MaterialDesc> =
        [(0, None), (1, Some(0)), (2, None), (3, Some(1)), (1, None)]
            .into_iter()
            .map(|(base, emissive)| MaterialDesc {
                base_color_texture: uses(base),
                emissive_texture: emissive.and_then(uses),
                ..Default::default()
            })
            .collect();
    let mut store = TextureStore::default();
    let mut warnings = Vec::new();
    let model = std::path::Path::new("scenes/model.gltf");
    let slots = add_model_textures(&mut store, model, &images, &materials, &mut warnings);
    let none = lambert::layout::NO_TEXTURE;
    assert_ne!(slots[0].base_color, none);
    assert_eq!(slots[0].emissive, none);
    assert_eq!(slots[1].base_color, none);
    assert_ne!(slots[1].emissive, none);
    assert_eq!(slots[2].base_color, none);
    assert_eq!(slots[3].base_color, none);
    assert!(slots.iter().all(|s| s.alpha == none));
    // Image 0 decoded once: 256 table words, 3 levels (4×2, 2×1, 1×1) of
    // 4 words and 11 texels, and two slots of 10 words.
    assert_eq!(store.words().len(), 256 + 12 + 11 + 20);
    // Its texels read back as the image (linear of sRGB 10, 20, 30).
    let c = Textures {
        words: store.words(),
    }
    .sample_texture(slots[0].base_color, Vec2::new(0.5, 0.5), 0);
    assert_eq!(c.x, linear_from_srgb(10) as f32 / 32768.0);
    assert_eq!(warnings.len(), 3, "{warnings:#?}");
    let missing = dir.path().join("missing.png").display().to_string();
    assert!(
        warnings[0].starts_with(&format!("scenes/model.gltf: {missing}"))
            && warnings[0].ends_with("materials 1, 3, 4 keep their colour without it"),
        "{}",
        warnings[0]
    );
    assert_eq!(
        warnings[1],
        "scenes/model.gltf: model.gltf image 2 (data URI): not a PNG or JPEG image; material 2 \
         keeps its colour without it"
    );
    assert!(
        warnings[2].starts_with("scenes/model.gltf: model.gltf image 3: not a readable PNG image")
            && warnings[2].ends_with("material 3 keeps its colour without it"),
        "{}",
        warnings[2]
    );
    // What `lambert info` lists.
    let report = describe_images(&images, &materials);
    assert_eq!(report[0].decoded, Ok((4, 2, "PNG")));
    assert_eq!(report[0].materials, [0, 1]);
    assert!(report[1].decoded.is_err());
    assert_eq!(report[1].materials, [1, 3, 4]);
}
