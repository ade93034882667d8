//! Every WGSL file validates with naga and every host struct matches its WGSL layout (no GPU needed).

mod common;

use std::mem::{offset_of, size_of};

use lambert::layout::*;
use lambert::shader_source::{HARDWARE_SOURCE, SOURCE};

fn module() -> naga::Module {
    naga::front::wgsl::parse_str(SOURCE).unwrap_or_else(|e| panic!("{}", e.emit_to_string(SOURCE)))
}

/// Both composed shaders validate (the ray-query module with ray queries
/// allowed), and they are made of every WGSL file under shaders/ (none
/// left out), none over 600 lines.
#[test]
fn every_wgsl_file_validates() {
    for (source, capabilities) in [
        (SOURCE, naga::valid::Capabilities::default()),
        (HARDWARE_SOURCE, naga::valid::Capabilities::RAY_QUERY),
    ] {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "wgsl") {
            let source = std::fs::read_to_string(&path).unwrap();
            assert!(
                SOURCE.contains(&source) || HARDWARE_SOURCE.contains(&source),
                "{} is in neither composed shader",
                path.display()
            );
            let lines = source.lines().count();
            assert!(lines <= 600, "{}: {lines} lines, over 600", path.display());
            count += 1;
        }
    }
    assert!(count >= 1, "no WGSL files found in {}", dir.display());
}

/// (size, [(member name, offset)]) of a WGSL struct, as naga lays it out.
fn reflect(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("WGSL has no struct {name}"));
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        panic!("{name} is not a struct")
    };
    let offsets = members
        .iter()
        .map(|m| (m.name.clone().unwrap(), m.offset))
        .collect();
    (layouter[handle].size, offsets)
}

macro_rules! check_layout {
    ($module:expr, $ty:ident { $($field:ident),* $(,)? }) => {{
        let (size, members) = reflect($module, stringify!($ty));
        assert_eq!(size as usize, size_of::<$ty>(), "size of {}", stringify!($ty));
        let host: Vec<(String, u32)> = vec![$((stringify!($field).to_string(), offset_of!($ty, $field) as u32)),*];
        assert_eq!(members, host, "member offsets of {}", stringify!($ty));
    }};
}

#[test]
fn host_structs_match_wgsl_layout() {
    let m = &module();
    assert_eq!(
        reflect(m, "ShadowQuery").0 as u64,
        lambert::gpu::SHADOW_QUERY_BYTES,
        "size of ShadowQuery"
    );
    assert_eq!(
        reflect(m, "WaveShading").0 as u64,
        lambert::gpu::WAVE_SHADING_BYTES,
        "size of WaveShading"
    );
    assert_eq!(
        reflect(m, "PathRecord").0 as u64,
        lambert::gpu::PATH_RECORD_BYTES,
        "size of PathRecord"
    );
    check_layout!(
        m,
        Params {
            eye,
            width,
            right,
            height,
            up,
            tan_half_x,
            forward,
            tan_half_y,
            background,
            num_triangles,
            ambient,
            num_spheres,
            tile_origin,
            num_lights,
            shadows,
            spp,
            seed,
            strata_x,
            sample_begin,
            sample_end,
            canary_loops,
            cone_spread,
            zero,
            tile_size,
            max_depth,
            _pad,
        }
    );
    check_layout!(
        m,
        Triangle {
            v0,
            material,
            v1,
            flags,
            v2,
            _pad
        }
    );
    check_layout!(m, TriangleNormals { n0, n1, n2 });
    check_layout!(m, TriangleTangents { t0, t1, t2 });
    assert_eq!(
        size_of::<Material>(),
        80,
        "Material: the shared design's 80 bytes"
    );
    assert_eq!(
        size_of::<Light>(),
        48,
        "Light: the shared design's 48 bytes"
    );
    check_layout!(
        m,
        Sphere {
            center,
            radius,
            material,
            _pad0,
            _pad1,
            _pad2
        }
    );
    check_layout!(
        m,
        Material {
            base_color,
            emission,
            alpha_mode,
            alpha_cutoff,
            base_color_texture,
            emissive_texture,
            alpha_texture,
            kind,
            metallic,
            roughness,
            metallic_roughness_texture,
            normal_texture,
            normal_scale,
            _pad,
        }
    );
    check_layout!(m, TriangleAttributes { colors, uvs, _pad });
    check_layout!(
        m,
        Light {
            vector,
            kind,
            color,
            cos_outer,
            direction,
            cos_inner
        }
    );
    check_layout!(
        m,
        Ray {
            origin,
            tmin,
            dir,
            tmax
        }
    );
    check_layout!(m, Hit { t, prim, u, v });
    check_layout!(m, PrimBlock { v, prims });
    check_layout!(
        m,
        CompressedNode {
            origin,
            exponents,
            child_base,
            block_base,
            child_meta,
            q
        }
    );
    check_layout!(
        m,
        ClosestPoint {
            point,
            prim,
            u,
            v,
            distance,
            _pad
        }
    );
    check_layout!(m, ListedHit { ray, prim, t, u, v });
    check_layout!(
        m,
        WindingNode {
            centre,
            radius,
            normal,
            first_child,
            child_count,
            first_prim,
            prim_count,
            _pad
        }
    );
}

/// The path integrator's lights' structs (shaders/layout.wgsl's lighting
/// part, shaders/entry_lights.wgsl).
#[test]
fn lighting_structs_match_wgsl_layout() {
    let m = &module();
    check_layout!(
        m,
        Emitter {
            kind,
            index,
            pmf,
            q,
            alias_bin,
            _pad0,
            _pad1,
            _pad2
        }
    );
    check_layout!(
        m,
        Lighting {
            environment_color,
            num_emitters,
            environment_width,
            environment_height,
            rotation_cos,
            rotation_sin,
            num_triangle_emitters,
            environment_pmf,
            total_power,
            flags
        }
    );
    check_layout!(
        m,
        SceneArrays {
            triangles,
            normals,
            attributes,
            tangents,
            nodes,
            blocks,
            spheres,
            materials,
            lights,
            textures,
            emitters,
            environment,
            environment_cdf,
            _pad0,
            _pad1,
            _pad2
        }
    );
    check_layout!(
        m,
        LightQuery {
            position,
            u_pick,
            normal,
            hit_prim,
            dir,
            distance,
            u,
            _pad
        }
    );
    check_layout!(
        m,
        LightAnswer {
            wi,
            distance,
            radiance,
            pdf,
            environment,
            environment_pdf,
            emitter_pdf,
            delta,
            _pad
        }
    );
}

#[test]
fn shader_constants_match_host() {
    let m = module();
    let constant = |name: &str| -> String { format!("{:?}", common::wgsl_constant(&m, name)) };
    let u32s = [
        ("NO_HIT", NO_HIT),
        ("LIGHT_POINT", LIGHT_POINT),
        ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
        ("LIGHT_SPOT", LIGHT_SPOT),
        ("MATERIAL_LAMBERT", MATERIAL_LAMBERT),
        ("MATERIAL_METALLIC_ROUGHNESS", MATERIAL_METALLIC_ROUGHNESS),
        ("FLAG_SMOOTH", FLAG_SMOOTH),
        ("MAX_DEPTH", lambert::bvh::MAX_DEPTH as u32),
        ("META_INTERIOR", META_INTERIOR),
        ("META_LEAF", META_LEAF),
        (
            "WORKGROUP_INVOCATIONS",
            lambert::layout::WORKGROUP_INVOCATIONS,
        ),
    ];
    for (name, value) in u32s {
        assert_eq!(constant(name), format!("Literal(U32({value}))"), "{name}");
    }
    assert_eq!(constant("FAR"), format!("Literal(F32({FAR:?}))"));
}

#[test]
fn overrides_named_by_the_host_exist() {
    let m = module();
    let scene = lambert::Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/spheres.toml"),
    )
    .unwrap();
    for (name, _) in lambert::gpu::specialisation(&scene) {
        assert!(
            m.overrides
                .iter()
                .any(|(_, o)| o.name.as_deref() == Some(name)),
            "the host sets override {name}, which the shader lacks"
        );
    }
}
