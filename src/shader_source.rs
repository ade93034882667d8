//! The GPU kernel's WGSL source: the files of `shaders/`, one per stage,
//! composed at build time in dependency order into the one module that naga
//! validates and wgpu compiles (docs/bvh.md lists the stages and their CPU
//! twins).

/// The whole shader: data layout, then each stage before those that call
/// it, then the entry points.
pub const SOURCE: &str = concat!(
    include_str!("../shaders/layout.wgsl"),
    "\n",
    include_str!("../shaders/math.wgsl"),
    "\n",
    include_str!("../shaders/fetch.wgsl"),
    "\n",
    include_str!("../shaders/intersect.wgsl"),
    "\n",
    include_str!("../shaders/traverse.wgsl"),
    "\n",
    include_str!("../shaders/texture.wgsl"),
    "\n",
    include_str!("../shaders/shade.wgsl"),
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
    include_str!("../shaders/entry_render.wgsl"),
    "\n",
    include_str!("../shaders/entry_shadows.wgsl"),
    "\n",
    include_str!("../shaders/entry_query.wgsl"),
    "\n",
    include_str!("../shaders/entry_proximity.wgsl"),
    "\n",
    include_str!("../shaders/entry_lights.wgsl"),
);
