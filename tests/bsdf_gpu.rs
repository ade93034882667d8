//! The GPU (lavapipe on CI) against the f32 twin: the shader's BSDF
//! (`bsdf_eval`, `bsdf_pdf`, `bsdf_sample`, the frame) and its math
//! (`approx_sin_cos`, `approx_acos`, `approx_atan2`, `approx_pow5`) give
//! the twin's bits on random inputs, grazing, sharp and degenerate ones
//! included.

mod common;

use glam::Vec3;
use lambert::cpu::f32 as single;
use lambert::layout::{MATERIAL_LAMBERT, MATERIAL_METALLIC_ROUGHNESS, Params};
use lambert::probe::Rng;

/// What the GPU test runs: the whole shader, and an entry point over an
/// array of cases. Its bindings sit in group 0 beside the kernel's
/// `params` (which `rounded` reads), at numbers no kernel binding takes.
const TWIN_SHADER: &str = r#"
struct BsdfCase {
    base_color: vec3<f32>,
    metallic: f32,
    wo: vec3<f32>,
    roughness: f32,
    wi: vec3<f32>,
    kind: u32,
    u: vec2<f32>,
    u_lobe: f32,
    _pad: f32,
    // approx_sin_cos(x), approx_acos(y) and approx_pow5(|y|), approx_atan2(z, w)
    math: vec4<f32>,
}
struct BsdfOut {
    eval: vec3<f32>,
    pdf: f32,
    wi: vec3<f32>,
    sample_pdf: f32,
    weight: vec3<f32>,
    ok: u32,
    local: vec3<f32>,
    sin: f32,
    world: vec3<f32>,
    cos: f32,
    acos: f32,
    atan2: f32,
    pow5: f32,
    _pad: f32,
}
@group(0) @binding(90) var<storage, read> bsdf_cases: array<BsdfCase>;
@group(0) @binding(91) var<storage, read_write> bsdf_out: array<BsdfOut>;
@compute @workgroup_size(64)
fn bsdf_twin(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&bsdf_cases) {
        return;
    }
    let c = bsdf_cases[id.x];
    let p = BsdfParams(c.base_color, c.metallic, c.roughness, c.kind);
    let s = bsdf_sample(p, c.wo, c.u, c.u_lobe);
    let frame = frame_from_normal(c.wo);
    let sc = approx_sin_cos(c.math.x);
    bsdf_out[id.x] = BsdfOut(bsdf_eval(p, c.wo, c.wi), bsdf_pdf(p, c.wo, c.wi), s.wi, s.pdf,
        s.weight, u32(s.ok), to_local(frame, c.wi), sc.x, to_world(frame, c.wi), sc.y,
        approx_acos(c.math.y), approx_atan2(c.math.z, c.math.w), approx_pow5(abs(c.math.y)), 0.0);
}
"#;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct BsdfCase {
    base_color: [f32; 3],
    metallic: f32,
    wo: [f32; 3],
    roughness: f32,
    wi: [f32; 3],
    kind: u32,
    u: [f32; 2],
    u_lobe: f32,
    _pad: f32,
    math: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct BsdfOut {
    eval: [f32; 3],
    pdf: f32,
    wi: [f32; 3],
    sample_pdf: f32,
    weight: [f32; 3],
    ok: u32,
    local: [f32; 3],
    sin: f32,
    world: [f32; 3],
    cos: f32,
    acos: f32,
    atan2: f32,
    pow5: f32,
    _pad: f32,
}

/// The twin's answer to a case, as the shader lays it out.
fn twin(c: &BsdfCase) -> BsdfOut {
    let p = single::BsdfParams {
        base_color: c.base_color.into(),
        metallic: c.metallic,
        roughness: c.roughness,
        kind: c.kind,
    };
    let (wo, wi) = (Vec3::from(c.wo), Vec3::from(c.wi));
    let s = single::bsdf_sample(p, wo, c.u.into(), c.u_lobe);
    let frame = single::frame_from_normal(wo);
    let (sin, cos) = single::approx_sin_cos(c.math[0]);
    BsdfOut {
        eval: single::bsdf_eval(p, wo, wi).into(),
        pdf: single::bsdf_pdf(p, wo, wi),
        wi: s.wi.into(),
        sample_pdf: s.pdf,
        weight: s.weight.into(),
        ok: s.ok as u32,
        local: single::to_local(frame, wi).into(),
        sin,
        world: single::to_world(frame, wi).into(),
        cos,
        acos: single::approx_acos(c.math[1]),
        atan2: single::approx_atan2(c.math[2], c.math[3]),
        pow5: single::approx_pow5(c.math[1].abs()),
        _pad: 0.0,
    }
}

/// A unit vector at cos θ = `cos` from +z, azimuth `phi`.
fn direction(cos: f64, phi: f64) -> Vec3 {
    let r = (1.0 - cos * cos).max(0.0).sqrt();
    Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, cos as f32)
}

/// Random cases over both kinds, roughness 0 to 1 (the α floor
/// included), wo and wi from the normal to grazing and below, and the
/// math functions' whole domains; then the degenerate ones: wo on the
/// normal, at the horizon, below it.
fn cases(n: usize) -> Vec<BsdfCase> {
    let mut rng = Rng(46);
    let mut cases: Vec<BsdfCase> = (0..n)
        .map(|i| {
            let mut unit = || rng.unit() as f32;
            let base_color = [unit(), unit(), unit()];
            let (metallic, roughness) =
                ([0.0, 1.0, unit()][i % 3], [0.0, 1.0, unit(), unit()][i % 4]);
            let kind = [MATERIAL_LAMBERT, MATERIAL_METALLIC_ROUGHNESS][(i % 5 != 0) as usize];
            let (u, u_lobe) = ([unit(), unit()], unit());
            let angle = (unit() * 2.0 - 1.0) * [7.0, 3216.0][i % 2];
            let math = [
                angle,
                unit() * 2.2 - 1.1,
                unit() * 2.0 - 1.0,
                unit() * 2.0 - 1.0,
            ];
            let (cos_o, cos_i) = (rng.range(-0.2, 1.0).powi(2), rng.range(-0.3, 1.0));
            let wo = direction(cos_o, rng.range(0.0, std::f64::consts::TAU));
            let wi = direction(cos_i, rng.range(0.0, std::f64::consts::TAU));
            BsdfCase {
                base_color,
                metallic,
                wo: wo.into(),
                roughness,
                wi: wi.into(),
                kind,
                u,
                u_lobe,
                _pad: 0.0,
                math,
            }
        })
        .collect();
    let degenerate = [
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        direction(1e-4, 1.0),
        direction(-1e-4, 2.0),
    ];
    for (i, wo) in degenerate.into_iter().enumerate() {
        let mut c = cases[i];
        c.wo = wo.into();
        c.math = [0.0, 1.0, 0.0, 0.0];
        cases.push(c);
    }
    cases
}

/// Runs TWIN_SHADER over `cases`.
fn run_twin_shader(cases: &[BsdfCase]) -> Vec<BsdfOut> {
    use wgpu::util::DeviceExt;
    let gpu = common::open_gpu();
    let device = &gpu.device;
    let source = format!("{}\n{TWIN_SHADER}", lambert::shader_source::SOURCE);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("bsdf twin"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("bsdf twin"),
        layout: None,
        module: &module,
        entry_point: Some("bsdf_twin"),
        compilation_options: Default::default(),
        cache: None,
    });
    // The kernel's uniform, all zero: `rounded`'s guard.
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::bytes_of(&Params::default()),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(cases),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let bytes = (cases.len() * size_of::<BsdfOut>()) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[(0, &params), (90, &input), (91, &output)].map(|(binding, buffer)| {
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        }),
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, bytes);
    gpu.queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let mapped = readback.get_mapped_range(..).unwrap().to_vec();
    bytemuck::cast_slice(&mapped).to_vec()
}

/// The shader gives the twin's bits for every case and every output:
/// eval, pdf, the sample (direction, weight, pdf, whether made), the
/// frame both ways, and the math functions.
#[test]
fn gpu_bsdf_and_math_equal_the_twin_bit_for_bit() {
    let cases = cases(100_000);
    let gpu = run_twin_shader(&cases);
    let words = size_of::<BsdfOut>() / 4;
    let mut differing = 0;
    for (i, (c, g)) in cases.iter().zip(&gpu).enumerate() {
        let t = twin(c);
        let (g_words, t_words): (&[u32], &[u32]) = (
            bytemuck::cast_slice(std::slice::from_ref(g)),
            bytemuck::cast_slice(std::slice::from_ref(&t)),
        );
        if g_words != t_words {
            if differing < 10 {
                println!("case {i} {c:?}:\n  GPU  {g:?}\n  twin {t:?}");
            }
            differing += 1;
        }
        assert_eq!(g_words.len(), words);
    }
    let made = gpu.iter().filter(|g| g.ok == 1).count();
    println!(
        "{} cases, {made} samples made, {differing} differing",
        cases.len()
    );
    assert!(made > cases.len() / 2, "{made} samples made");
    assert_eq!(differing, 0, "{differing} cases differ from the twin");
}
