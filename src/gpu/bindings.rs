//! The shader's bindings, one named table per bind group layout: the
//! layouts and the bind groups are built from these tables, so no binding
//! number is written anywhere else. tests/bindings.rs checks every entry
//! against naga's reflection of the shader, and every shader binding
//! against the tables.

/// What a binding holds, as the bind group layout declares it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    Uniform,
    /// A read-only storage buffer.
    Storage,
    /// A read-write storage buffer.
    StorageWrite,
    /// A read-only rgba32uint storage texture (`BvhStorage::Texels`).
    Texels,
    /// A write-only r32uint storage texture (`loop_status`, one texel).
    FlagTexel,
    /// A top-level acceleration structure (`--accel hardware`).
    AccelerationStructure,
}

/// One binding: the shader's name for it, its number, its kind.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub name: &'static str,
    pub binding: u32,
    pub kind: BindingKind,
}

/// The bindings of one bind group layout, at `group` in the pipelines.
#[derive(Debug)]
pub struct BindingTable {
    pub label: &'static str,
    pub group: u32,
    pub entries: &'static [Binding],
}

/// The first `size` bytes of `buffer` as a binding: the list entry points
/// stop at `arrayLength`, so a batch is bound to its own length.
pub(super) fn leading_bytes(buffer: &wgpu::Buffer, size: u64) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: wgpu::BufferSize::new(size),
    })
}

const fn bind(name: &'static str, binding: u32, kind: BindingKind) -> Binding {
    Binding {
        name,
        binding,
        kind,
    }
}

use BindingKind::{AccelerationStructure, FlagTexel, Storage, StorageWrite, Texels, Uniform};

/// Group 0 of every pipeline: the resident scene.
pub const SCENE: BindingTable = BindingTable {
    label: "scene",
    group: 0,
    entries: &[
        bind("params", 0, Uniform),
        bind("scene_words", 1, Storage),
        bind("arrays", 2, Uniform),
        bind("scene_words_hi", 8, Storage),
        bind("loop_status", 12, FlagTexel),
        bind("bvh_node_texels", 13, Texels),
        bind("bvh_block_texels", 14, Texels),
        bind("triangle_texels", 18, Texels),
        bind("lighting", 23, Uniform),
    ],
};

const OUT_PRIM: Binding = bind("out_prim", 1, StorageWrite);

const TILE_SUMS: Binding = bind("tile_sums", 6, StorageWrite);
const PIXEL_LIST_INPUT: Binding = bind("pixel_list", 4, Storage);

/// Group 1 of `render`: a tile's pixels.
pub const IMAGE_TILE: BindingTable = BindingTable {
    label: "image tile",
    group: 1,
    entries: &[OUT_PRIM, TILE_SUMS],
};

/// Group 1 of the wavefront (`render_primary`, `render_list_primary`,
/// `render_shadows` and `render_resolve`).
pub const WAVEFRONT: BindingTable = BindingTable {
    label: "image tile, wavefront",
    group: 1,
    entries: &[
        OUT_PRIM,
        TILE_SUMS,
        PIXEL_LIST_INPUT,
        bind("wave_shading", 7, StorageWrite),
        bind("shadow_queue", 8, StorageWrite),
        bind("wave_counts", 9, StorageWrite),
        bind("wave_workgroups", 10, StorageWrite),
        bind("resolve_pixels", 19, StorageWrite),
    ],
};

/// Group 1 of the path integrator's wavefront (shaders/entry_paths.wgsl):
/// the tile's or the pixel list's, the paths, their queues (two halves,
/// swapped from bounce to bounce), their shadow rays, the counts and the indirect
/// dispatches.
pub const PATH_WAVE: BindingTable = BindingTable {
    label: "image tile, path wavefront",
    group: 1,
    entries: &[
        OUT_PRIM,
        TILE_SUMS,
        PIXEL_LIST_INPUT,
        bind("shadow_queue", 8, StorageWrite),
        bind("path_records", 24, StorageWrite),
        bind("path_queues", 25, StorageWrite),
        bind("path_counts", 27, StorageWrite),
        bind("path_workgroups", 28, StorageWrite),
    ],
};

/// Group 1 of `trace_rays`: its input, then its output (`run_list`).
pub const RAYS: BindingTable = BindingTable {
    label: "rays",
    group: 1,
    entries: &[bind("rays", 2, Storage), bind("hits", 3, StorageWrite)],
};

/// Group 1 of `render_pixel_list`: its input, then its output.
pub const PIXEL_LIST: BindingTable = BindingTable {
    label: "pixel list",
    group: 1,
    entries: &[PIXEL_LIST_INPUT, bind("pixel_results", 5, StorageWrite)],
};

/// Group 1 of the geometric queries (`closest_points`, `winding_numbers`,
/// `count_hits`, `list_hits`; shaders/entry_proximity.wgsl): each binds
/// them all and uses its own.
pub const PROXIMITY: BindingTable = BindingTable {
    label: "proximity",
    group: 1,
    entries: &[
        bind("rays", 2, Storage),
        bind("query_points", 11, Storage),
        bind("query_scalars", 12, Storage),
        bind("closest_out", 13, StorageWrite),
        bind("winding_out", 14, StorageWrite),
        bind("winding_nodes", 15, Storage),
        bind("winding_prims", 16, Storage),
        bind("hit_counts", 17, StorageWrite),
        bind("listed_hits", 18, StorageWrite),
    ],
};

/// Group 1 of `probe_lights`: its queries, then its answers.
pub const LIGHT_PROBE: BindingTable = BindingTable {
    label: "light probe",
    group: 1,
    entries: &[
        bind("light_queries", 20, Storage),
        bind("light_answers", 21, StorageWrite),
    ],
};

/// Group 2 of every pipeline under `--accel hardware`, in its module alone
/// (`TABLES` are both modules'): the scene's acceleration structures
/// (shaders/hardware_trace.wgsl, src/gpu/hardware.rs).
pub const ACCELERATION: BindingTable = BindingTable {
    label: "acceleration",
    group: 2,
    entries: &[
        bind("scene_tlas", 0, AccelerationStructure),
        bind("hardware_runs", 1, Storage),
    ],
};

/// Every table.
pub const TABLES: [&BindingTable; 8] = [
    &SCENE,
    &IMAGE_TILE,
    &WAVEFRONT,
    &PATH_WAVE,
    &RAYS,
    &PIXEL_LIST,
    &PROXIMITY,
    &LIGHT_PROBE,
];

/// Why an adapter with `limits` cannot run the kernel, if it cannot: a
/// pipeline binds the scene's group and one second group, so it needs the
/// scene's storage buffers (and storage textures) and the most of any
/// required pass's second group, within the adapter's per-stage limits:
/// the megakernel's, ray queries' and pixel lists' (4 storage buffers in
/// all, within WebGPU's default 8). The wavefronts' passes, which bind up
/// to 10 (what browsers allow at most), are used where they fit
/// (`fits_wavefront`). Without this check wgpu fails later with "Too many
/// bindings" and `auto` never falls back.
pub fn unmet_limits(limits: &wgpu::Limits) -> Option<String> {
    unmet_limits_with(limits, &REQUIRED_SECONDS, &[])
}

/// Whether `limits` bind the passes of the direct integrator's wavefront,
/// or of the path integrator's (`path`); in the ray-query module
/// (`hardware`) with its group 2 too.
pub fn fits_wavefront(limits: &wgpu::Limits, path: bool, hardware: bool) -> bool {
    let table = if path { &PATH_WAVE } else { &WAVEFRONT };
    let extra: &[&BindingTable] = if hardware { &[&ACCELERATION] } else { &[] };
    unmet_limits_with(limits, &[table], extra).is_none()
}

/// `unmet_limits` of the hardware module, whose pipelines bind
/// `ACCELERATION` too.
pub(super) fn unmet_hardware_limits(limits: &wgpu::Limits) -> Option<String> {
    unmet_limits_with(limits, &REQUIRED_SECONDS, &[&ACCELERATION])
}

/// `unmet_limits` of the geometric queries' passes (`PROXIMITY`), checked
/// when they are first built: a browser's adapter (10 storage buffers a
/// stage) renders but cannot bind them.
pub(super) fn unmet_proximity_limits(limits: &wgpu::Limits) -> Option<String> {
    unmet_limits_with(limits, &[&PROXIMITY], &[])
}

/// The second groups of the passes every render and ray query may need:
/// every table's but the scene's, the wavefronts' (used where they fit)
/// and the geometric queries' (checked when first built).
const REQUIRED_SECONDS: [&BindingTable; 4] = [&IMAGE_TILE, &RAYS, &PIXEL_LIST, &LIGHT_PROBE];

/// Whether `limits` hold the scene's group, the largest of `seconds` and
/// the groups `extra` bound by every pipeline too.
fn unmet_limits_with(
    limits: &wgpu::Limits,
    seconds: &[&BindingTable],
    extra: &[&BindingTable],
) -> Option<String> {
    let most = |kind: fn(BindingKind) -> bool| {
        let count = |table: &BindingTable| table.entries.iter().filter(|e| kind(e.kind)).count();
        let second = seconds.iter().map(|t| count(t)).max().unwrap_or(0);
        (count(&SCENE) + second + extra.iter().map(|t| count(t)).sum::<usize>()) as u32
    };
    let short = |what: &str, has: u32, needs: u32| {
        (has < needs).then(|| {
            format!(
                "it binds at most {has} {what} per shader stage and lambert's kernel binds {needs}"
            )
        })
    };
    [
        (
            "storage buffers",
            limits.max_storage_buffers_per_shader_stage,
            most(|k| matches!(k, Storage | StorageWrite)),
        ),
        (
            "storage textures",
            limits.max_storage_textures_per_shader_stage,
            most(|k| matches!(k, Texels | FlagTexel)),
        ),
        (
            "acceleration structures",
            limits.max_acceleration_structures_per_shader_stage,
            most(|k| k == AccelerationStructure),
        ),
    ]
    .into_iter()
    .find_map(|(what, has, needs)| short(what, has, needs))
}

impl BindingTable {
    pub(super) fn layout(&self, device: &wgpu::Device) -> wgpu::BindGroupLayout {
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let entries: Vec<wgpu::BindGroupLayoutEntry> = self
            .entries
            .iter()
            .map(|entry| wgpu::BindGroupLayoutEntry {
                binding: entry.binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: match entry.kind {
                    Uniform => buffer(wgpu::BufferBindingType::Uniform),
                    Storage => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
                    StorageWrite => buffer(wgpu::BufferBindingType::Storage { read_only: false }),
                    Texels => wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::ReadOnly,
                        format: wgpu::TextureFormat::Rgba32Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    FlagTexel => wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: wgpu::TextureFormat::R32Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    AccelerationStructure => wgpu::BindingType::AccelerationStructure {
                        vertex_return: false,
                    },
                },
                count: None,
            })
            .collect();
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(self.label),
            entries: &entries,
        })
    }

    /// A bind group of `layout` (this table's) with each of the table's
    /// bindings given by name in `resources`.
    pub(super) fn bind_group(
        &self,
        device: &wgpu::Device,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        resources: Vec<(&str, wgpu::BindingResource<'_>)>,
    ) -> wgpu::BindGroup {
        assert_eq!(
            resources.len(),
            self.entries.len(),
            "{}: one resource per binding",
            self.label
        );
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .into_iter()
            .map(|(name, resource)| wgpu::BindGroupEntry {
                binding: self.binding(name),
                resource,
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries: &entries,
        })
    }

    fn binding(&self, name: &str) -> u32 {
        self.entries
            .iter()
            .find(|e| e.name == name)
            .unwrap_or_else(|| panic!("the {} bind group has no binding {name}", self.label))
            .binding
    }
}
