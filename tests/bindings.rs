//! The host's bind group tables (`lambert::gpu::bindings`) against naga's
//! reflection of the shader: every entry is a global of the shader at that
//! group and binding, of that kind and access, and every shader binding has
//! an entry. No GPU needed.

use lambert::gpu::bindings::{
    ACCELERATION, BindingKind, BindingTable, TABLES, fits_wavefront, unmet_limits,
};
use lambert::gpu::{HARDWARE_SOURCE, SHADER_SOURCE};

/// Each module with the tables its pipelines bind: the compute module
/// `TABLES`, the ray-query module (`--accel hardware`) those and
/// `ACCELERATION`.
fn modules() -> Vec<(naga::Module, Vec<&'static BindingTable>)> {
    let parse = |source: &str| {
        naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)))
    };
    let hardware_tables = TABLES.iter().copied().chain([&ACCELERATION]).collect();
    vec![
        (parse(SHADER_SOURCE), TABLES.to_vec()),
        (parse(HARDWARE_SOURCE), hardware_tables),
    ]
}

/// The kind a bind group layout must give `global`, read from the shader,
/// or why it has none.
fn shader_kind(
    module: &naga::Module,
    global: &naga::GlobalVariable,
) -> Result<BindingKind, String> {
    use naga::{AddressSpace, ImageClass, ImageDimension, StorageAccess, TypeInner};
    match (global.space, &module.types[global.ty].inner) {
        (AddressSpace::Uniform, _) => Ok(BindingKind::Uniform),
        (AddressSpace::Storage { access }, _) if access.contains(StorageAccess::STORE) => {
            Ok(BindingKind::StorageWrite)
        }
        (AddressSpace::Storage { .. }, _) => Ok(BindingKind::Storage),
        (
            AddressSpace::Handle,
            TypeInner::AccelerationStructure {
                vertex_return: false,
            },
        ) => Ok(BindingKind::AccelerationStructure),
        (
            AddressSpace::Handle,
            TypeInner::Image {
                dim: ImageDimension::D2,
                arrayed: false,
                class,
            },
        ) => match class {
            ImageClass::Storage {
                format: naga::StorageFormat::Rgba32Uint,
                access,
            } if *access == StorageAccess::LOAD => Ok(BindingKind::Texels),
            ImageClass::Storage {
                format: naga::StorageFormat::R32Uint,
                access,
            } if *access == StorageAccess::STORE => Ok(BindingKind::FlagTexel),
            other => Err(format!("a 2D image of class {other:?}")),
        },
        (space, inner) => Err(format!("{space:?} {inner:?}")),
    }
}

/// The shader's bound globals: (name, group, binding, kind or why not).
fn shader_bindings(module: &naga::Module) -> Vec<(String, u32, u32, Result<BindingKind, String>)> {
    module
        .global_variables
        .iter()
        .filter_map(|(_, g)| {
            let b = g.binding.as_ref()?;
            Some((
                g.name.clone().expect("bound globals are named"),
                b.group,
                b.binding,
                shader_kind(module, g),
            ))
        })
        .collect()
}

#[test]
fn every_table_entry_is_the_shader_binding_of_that_name() {
    for (module, tables) in modules() {
        every_entry_is_bound(&module, &tables);
    }
}

fn every_entry_is_bound(module: &naga::Module, tables: &[&BindingTable]) {
    let shader = shader_bindings(module);
    for table in tables {
        for entry in table.entries {
            let (_, group, binding, kind) = shader
                .iter()
                .find(|(name, ..)| name == entry.name)
                .unwrap_or_else(|| panic!("{}: the shader binds no {}", table.label, entry.name));
            assert_eq!(
                (*group, *binding),
                (table.group, entry.binding),
                "{}: (group, binding) of {}",
                table.label,
                entry.name
            );
            assert_eq!(
                kind.as_ref(),
                Ok(&entry.kind),
                "{}: kind of {}",
                table.label,
                entry.name
            );
        }
    }
}

#[test]
fn every_shader_binding_has_a_table_entry() {
    for (module, tables) in modules() {
        every_binding_has_an_entry(&module, &tables);
    }
}

fn every_binding_has_an_entry(module: &naga::Module, tables: &[&BindingTable]) {
    let shader = shader_bindings(module);
    assert!(!shader.is_empty(), "the shader binds nothing");
    let in_tables = |name: &str, group: u32, binding: u32| {
        tables.iter().any(|t: &&BindingTable| {
            t.group == group
                && t.entries
                    .iter()
                    .any(|e| e.name == name && e.binding == binding)
        })
    };
    for (name, group, binding, _) in &shader {
        assert!(
            in_tables(name, *group, *binding),
            "the shader's {name} (group {group}, binding {binding}) is in no binding table"
        );
    }
}

#[test]
fn no_table_binds_a_number_twice() {
    for table in TABLES.iter().chain([&&ACCELERATION]) {
        let mut numbers: Vec<u32> = table.entries.iter().map(|e| e.binding).collect();
        numbers.sort();
        let len = numbers.len();
        numbers.dedup();
        assert_eq!(
            numbers.len(),
            len,
            "{}: a binding number twice",
            table.label
        );
    }
}

/// WebGPU's default limits (8 storage buffers and 4 storage textures a
/// stage) run every required pass: the scene's group and the megakernel's,
/// ray queries' and pixel lists'; a browser's 10 (Chromium's SwiftShader
/// and its tier for real GPUs) run the wavefronts too. Fewer are refused in
/// words, naming the limit; the geometric queries, which bind more, are
/// checked apart.
#[test]
fn webgpu_default_and_browser_limits_run_the_render_passes() {
    let default = wgpu::Limits::default();
    assert_eq!(default.max_storage_buffers_per_shader_stage, 8);
    assert_eq!(unmet_limits(&default), None);
    assert!(!fits_wavefront(&default, false, false) && !fits_wavefront(&default, true, false));
    let browser = wgpu::Limits {
        max_storage_buffers_per_shader_stage: 10,
        ..default.clone()
    };
    assert!(fits_wavefront(&browser, false, false) && fits_wavefront(&browser, true, false));
    // The ray-query module's group 2 binds one more.
    assert!(!fits_wavefront(&browser, false, true));
    let fewer = wgpu::Limits {
        max_storage_buffers_per_shader_stage: 3,
        ..default.clone()
    };
    let why = unmet_limits(&fewer).expect("3 storage buffers refused");
    assert!(
        why.contains("at most 3 storage buffers") && why.contains("binds 4"),
        "{why}"
    );
    let textures = wgpu::Limits {
        max_storage_textures_per_shader_stage: 3,
        ..default
    };
    let why = unmet_limits(&textures).expect("3 storage textures refused");
    assert!(why.contains("storage textures"), "{why}");
}
