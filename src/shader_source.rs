//! The GPU kernel's WGSL source: the files of `shaders/`, one per stage,
//! composed at build time in dependency order into the one module that naga
//! validates and wgpu compiles (docs/shaders.md lists the stages and their
//! CPU twins). Two compositions of the same stages, differing in `trace`
//! alone: the compute traversal's, and the ray query's (`--accel
//! hardware`), whose module opens with its own layout (an `enable` that
//! adapters without ray queries reject, its override and bindings).

/// The stages in order (each before those that call it), then the entry
/// points, with `$trace`'s file as the traversal the stages call, after
/// `$head` (the module's first files, a comma after each).
macro_rules! compose {
    ([$($head:tt)*] $trace:literal) => {
        concat!(
            $($head)*
            include_str!("../shaders/layout.wgsl"),
            "\n",
            include_str!("../shaders/math.wgsl"),
            "\n",
            include_str!("../shaders/bsdf.wgsl"),
            "\n",
            include_str!("../shaders/fetch.wgsl"),
            "\n",
            include_str!("../shaders/intersect.wgsl"),
            "\n",
            include_str!("../shaders/traverse.wgsl"),
            "\n",
            include_str!($trace),
            "\n",
            include_str!("../shaders/texture.wgsl"),
            "\n",
            include_str!("../shaders/shade.wgsl"),
            "\n",
            include_str!("../shaders/material.wgsl"),
            "\n",
            include_str!("../shaders/lights.wgsl"),
            "\n",
            include_str!("../shaders/sample.wgsl"),
            "\n",
            include_str!("../shaders/closest.wgsl"),
            "\n",
            include_str!("../shaders/winding.wgsl"),
            "\n",
            include_str!("../shaders/all_hits.wgsl"),
            "\n",
            include_str!("../shaders/integrator.wgsl"),
            "\n",
            include_str!("../shaders/entry_render.wgsl"),
            "\n",
            include_str!("../shaders/entry_shadows.wgsl"),
            "\n",
            include_str!("../shaders/entry_paths.wgsl"),
            "\n",
            include_str!("../shaders/entry_query.wgsl"),
            "\n",
            include_str!("../shaders/entry_proximity.wgsl"),
            "\n",
            include_str!("../shaders/entry_lights.wgsl"),
        )
    };
}

/// The whole shader, tracing through the compute BVH.
pub const SOURCE: &str = compose!([] "../shaders/trace.wgsl");

/// The whole shader, tracing through ray queries (`--accel hardware`).
pub const HARDWARE_SOURCE: &str = compose!(
    [include_str!("../shaders/hardware_layout.wgsl"), "\n",]
    "../shaders/hardware_trace.wgsl"
);
