//! The CPU path's ray queries: rays in parallel chunks, several rays in
//! turn per thread (prefetch.rs chooses how many), hits (and normals)
//! handed over chunk by chunk, and the oracle's query in double precision.

use rayon::prelude::*;

use super::packet::{PACKET, trace_packets};
use super::prefetch::{INTERLEAVED_INCOHERENT_RAYS, INTERLEAVED_RAYS, LARGE_BVH_BYTES};
use super::render::twin_stack_entries;
use super::simd::{check_runs, with_simd};
use super::{CpuKernel, f32, f64};
use crate::layout::{self, NO_HIT};
use crate::scene::{Intersect, Scene};

/// The GPU's twin of a ray query (as `render_gpu_twin`): the same hits as
/// the GPU's, primitive for primitive and bit for bit, where the GPU's
/// arithmetic is IEEE's.
pub fn trace_rays_gpu_twin(
    scene: &Scene,
    rays: &[layout::Ray],
    any_hit: bool,
    intersect: Intersect,
) -> Vec<layout::Hit> {
    let nodes = crate::cwbvh::compress(&scene.bvh);
    let mut kernel = f32::Kernel::new_for(scene, false);
    kernel.intersect = intersect;
    kernel.compressed = Some(&nodes);
    kernel.stack_entries = twin_stack_entries(scene);
    let local = scene.placement().localize(rays);
    let mut hits: Vec<layout::Hit> = local
        .rays
        .par_iter()
        .map(|ray| query_hit(kernel.trace(f32::Ray::from_query(ray), any_hit)))
        .collect();
    local.to_world(&mut hits);
    hits
}

/// Traces a ray query on the CPU in single precision, as the GPU does:
/// closest hits, or with `any_hit` the first hit found. Misses report
/// `layout::Hit::MISS`.
pub fn trace_rays(scene: &Scene, rays: &[layout::Ray], any_hit: bool) -> Vec<layout::Hit> {
    trace_rays_with(scene, rays, any_hit, scene.intersect, CpuKernel::active())
}

/// `trace_rays` with a given ray/triangle test and CPU kernel (one this
/// CPU runs).
pub fn trace_rays_with(
    scene: &Scene,
    rays: &[layout::Ray],
    any_hit: bool,
    intersect: Intersect,
    cpu_kernel: CpuKernel,
) -> Vec<layout::Hit> {
    trace_rays_as(
        scene,
        rays,
        any_hit,
        intersect,
        cpu_kernel,
        QueryKernel::Packets,
    )
}

/// Which kernel a query runs (`trace_rays_as`): the default `Packets`,
/// and the portable originals the faster kernels are tested against, bit
/// for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QueryKernel {
    /// Every feature checked at run time (`f32::ALL_FEATURES`: alpha
    /// masks, spheres and the triangle test), one ray at a time: the
    /// original of the variants specialised for what a scene holds.
    Generic,
    /// Compiled for what the scene holds (`Kernel::features`), one ray at
    /// a time: the original of the coherent rays' packets (packet.rs).
    Single,
    /// `Single`, and coherent rays in packets where the scene allows.
    Packets,
}

/// `trace_rays_with` through `which` kernel.
pub fn trace_rays_as(
    scene: &Scene,
    rays: &[layout::Ray],
    any_hit: bool,
    intersect: Intersect,
    cpu_kernel: CpuKernel,
    which: QueryKernel,
) -> Vec<layout::Hit> {
    // Written by the threads themselves: filling it first on one thread
    // would cost a twentieth of the trace.
    let mut hits: Vec<layout::Hit> = Vec::with_capacity(rays.len());
    let out = SharedOut(hits.as_mut_ptr());
    trace_each(
        scene,
        QueryRays::Slice(rays),
        QueryOptions {
            any_hit,
            intersect,
            cpu_kernel,
            normals: false,
        },
        RayFrame::World,
        which,
        &|chunk| {
            // SAFETY: chunks are disjoint and within the capacity.
            unsafe {
                std::ptr::copy_nonoverlapping(
                    chunk.hits.as_ptr(),
                    out.at(chunk.start),
                    chunk.hits.len(),
                )
            }
        },
    );
    // SAFETY: every chunk was written.
    unsafe { hits.set_len(rays.len()) };
    hits
}

/// A buffer that parallel threads write disjoint ranges of (the chunks of
/// `trace_rays_each`).
pub struct SharedOut<T>(*mut T);
// SAFETY: each thread writes its own range.
unsafe impl<T> Sync for SharedOut<T> {}
unsafe impl<T> Send for SharedOut<T> {}
impl<T> SharedOut<T> {
    pub fn new(buffer: &mut [T]) -> SharedOut<T> {
        SharedOut(buffer.as_mut_ptr())
    }

    /// Over `vec`'s spare capacity (elements written before its length
    /// is set).
    pub fn new_spare(vec: &mut Vec<T>) -> SharedOut<T> {
        SharedOut(vec.as_mut_ptr())
    }

    /// # Safety
    /// `start` within the buffer, its range written by one thread at a
    /// time, and the buffer alive and not otherwise borrowed meanwhile.
    pub unsafe fn at(&self, start: usize) -> *mut T {
        unsafe { self.0.add(start) }
    }
}

/// A ray query's rays: a slice, or `count` rays that `fill(start, out)`
/// writes (rays start.. into all of `out`), assembled chunk by chunk as
/// they are traced (the Python binding's arrays: no pass over all the rays
/// before the trace, nor a buffer of them), answering what it did with
/// them (`Filled`). `ahead(rows)` starts loading what rays `rows` will
/// read and write (a thread's next chunk's): asked four packets at a
/// time while a chunk traces in packets (all at once, the loads stalled
/// it on the CPU's few outstanding misses), and for the whole chunk
/// before a chunk of single rays.
#[derive(Clone, Copy)]
pub enum QueryRays<'a> {
    Slice(&'a [layout::Ray]),
    Fill(
        usize,
        &'a (dyn Fn(usize, &mut [std::mem::MaybeUninit<layout::Ray>]) -> Filled + Sync),
        &'a (dyn Fn(std::ops::Range<usize>) + Sync),
    ),
}

/// What a query's fill did with a chunk's rays (`QueryRays::Fill`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filled {
    /// Wrote them as given.
    AsGiven,
    /// As given, in the world's frame, every origin near the scene
    /// (`Placement::near_within`): none for the trace to move.
    Near,
    /// Moved some along themselves into the scene's frame
    /// (`Placement::local_ray`'s shift; `TracedChunk::moved`).
    Moved,
}

impl QueryRays<'_> {
    pub fn len(&self) -> usize {
        match self {
            QueryRays::Slice(rays) => rays.len(),
            QueryRays::Fill(count, ..) => *count,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Ray `i`.
    pub fn ray(&self, i: usize) -> layout::Ray {
        match self {
            QueryRays::Slice(rays) => rays[i],
            QueryRays::Fill(_, fill, _) => {
                let mut one = [std::mem::MaybeUninit::uninit()];
                fill(i, &mut one);
                // SAFETY: `fill` writes all of `out`.
                unsafe { one[0].assume_init() }
            }
        }
    }
}

/// How `trace_rays_each` traces.
#[derive(Clone, Copy, Debug)]
pub struct QueryOptions {
    /// The first hit found rather than the closest.
    pub any_hit: bool,
    pub intersect: Intersect,
    pub cpu_kernel: CpuKernel,
    /// Each hit's geometric normal too (`scene::hit_normal`'s, bit for bit),
    /// taken from the leaf block the kernel just read.
    pub normals: bool,
}

/// A traced chunk of a query: its first ray's index, its rays' hits and,
/// when asked for, their normals (else empty).
pub struct TracedChunk<'a> {
    pub start: usize,
    pub hits: &'a [layout::Hit],
    pub normals: &'a [[f32; 3]],
    /// Whether the hits may lie on rays the caller moved along themselves
    /// (`RayFrame::Local`: a slice's, or those a fill said it moved), to
    /// be moved back (`placement::world_hit`); false where the hits are on
    /// the rays as the caller gave them.
    pub moved: bool,
}

/// The frame a query's rays are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayFrame {
    /// World coordinates (as in a ray file): each ray is moved into the
    /// scene's frame (`Placement::local_ray`), and its hit back.
    World,
    /// The scene's frame already (from `Placement::local_ray`, say, for
    /// rays given in f64); hits in that frame.
    Local,
}

/// Traces `rays`, in `frame`, in parallel chunks, handing each chunk's
/// hits (with the index of its first ray) to `each` while they are hot in
/// cache: the Python binding fills its numpy columns this way, with no hit
/// buffer between.
pub fn trace_rays_each(
    scene: &Scene,
    rays: QueryRays,
    options: QueryOptions,
    frame: RayFrame,
    // Not generic: a generic would be compiled in the caller's crate, with
    // its codegen settings, and the kernel ran up to 40% slower there.
    each: &(dyn Fn(&TracedChunk) + Sync),
) {
    trace_each(scene, rays, options, frame, QueryKernel::Packets, each)
}

/// `trace_rays_each` through `which` kernel.
fn trace_each(
    scene: &Scene,
    rays: QueryRays,
    options: QueryOptions,
    frame: RayFrame,
    which: QueryKernel,
    each: &(dyn Fn(&TracedChunk) + Sync),
) {
    use std::mem::MaybeUninit;
    // A chunk's rays, hits and normals stay within L1 (48 KiB a core on
    // current servers): 1024 a chunk (60 KiB) cost the Python binding's
    // camera rays through the dragon 2–3% (docs/benchmarks.md).
    const CHUNK: usize = 256;
    const AHEAD: usize = 4 * PACKET;
    let QueryOptions {
        any_hit,
        intersect,
        cpu_kernel,
        normals,
    } = options;
    check_runs(cpu_kernel);
    let mut kernel = f32::Kernel::new_for(scene, cpu_kernel.ymm_boxes());
    kernel.intersect = intersect;
    let placement = scene.placement();
    let large = scene.bvh.device_bytes() > LARGE_BVH_BYTES;
    let vector_sort = cpu_kernel.vector_sort();
    // Chosen once for the query: a scene of watertight-tested triangles
    // alone (the usual one) takes the kernel without the alpha test, the
    // sphere loop and the choice of triangle test; any other the generic.
    let triangles_only = which != QueryKernel::Generic && kernel.features() == 0;
    let nearby = nearby(scene);
    // Judged once for the whole query: judged per chunk, it cost camera
    // rays through small models up to 5%.
    let coherent = coherent(&rays, nearby);
    let incoherent = (large || vector_sort) && !coherent;
    let packets = which == QueryKernel::Packets && packets_apply(&kernel, coherent);
    // The whole chunk's (the rays' placing too): an Intel core slows for
    // a while after any 512-bit instruction.
    let cpu_kernel = match packets {
        true => cpu_kernel.narrow_on_intel(),
        false => cpu_kernel,
    };
    (0..rays.len().div_ceil(CHUNK))
        .into_par_iter()
        .for_each(|index| {
            let start = index * CHUNK;
            let len = CHUNK.min(rays.len() - start);
            let mut own = [MaybeUninit::<layout::Ray>::uninit(); CHUNK];
            let (chunk_rays, filled) = match rays {
                // A local slice's rays may have been moved.
                QueryRays::Slice(all) => (&all[start..start + len], Filled::Moved),
                QueryRays::Fill(_, fill, _) => {
                    let filled = fill(start, &mut own[..len]);
                    // SAFETY: `fill` writes all of its buffer.
                    let rays = unsafe { &*(&own[..len] as *const [_] as *const [layout::Ray]) };
                    (rays, filled)
                }
            };
            // Moved rays on the heap, and only where some ray moves: two
            // zeroed stack arrays a chunk cost camera rays 3%.
            let moved = if frame == RayFrame::World && filled != Filled::Near {
                // SAFETY: the kernel was checked.
                unsafe {
                    with_simd(
                        cpu_kernel,
                        #[inline(always)]
                        || placement.localize_chunk(chunk_rays),
                    )
                }
            } else {
                None
            };
            let chunk_rays = moved.as_ref().map_or(chunk_rays, |(local, _)| &local[..]);
            // This thread's next chunk, most likely (its share runs in
            // order), AHEAD rays at a time.
            let ahead = |i: usize| {
                if let QueryRays::Fill(count, _, ahead) = rays {
                    let from = (start + CHUNK + i).min(count);
                    ahead(from..(from + AHEAD).min(count));
                }
            };
            let mut buffer = [MaybeUninit::<layout::Hit>::uninit(); CHUNK];
            let hits = &mut buffer[..len];
            let mut normal_buffer = [MaybeUninit::<[f32; 3]>::uninit(); CHUNK];
            let normal_out = &mut normal_buffer[..if normals { len } else { 0 }];
            // One `with_simd` per kind of chunk, each then a function of its
            // own: in one, camera rays through small models ran 2% slower,
            // and incoherent ones gained about half as much from
            // VECTOR_SORT.
            macro_rules! chunk {
                ($lanes:expr, $prefetch:expr, $vector_sort:expr) => {
                    if triangles_only {
                        chunk!($lanes, $prefetch, $vector_sort, 0)
                    } else {
                        chunk!($lanes, $prefetch, $vector_sort, f32::ALL_FEATURES)
                    }
                };
                ($lanes:expr, $prefetch:expr, $vector_sort:expr, $features:expr) => {
                    // SAFETY: the kernel was checked; VECTOR_SORT only
                    // where `vector_sort` says the CPU can.
                    unsafe {
                        with_simd(
                            cpu_kernel,
                            #[inline(always)]
                            || {
                                trace_chunk::<{ $lanes }, $prefetch, $vector_sort, { $features }>(
                                    &kernel, chunk_rays, hits, normal_out, any_hit,
                                )
                            },
                        )
                    }
                };
            }
            if packets {
                let kernel_ref = &kernel;
                // SAFETY: the kernel was checked.
                unsafe {
                    with_simd(
                        cpu_kernel,
                        #[inline(always)]
                        || {
                            trace_packets(
                                kernel_ref,
                                chunk_rays,
                                cpu_kernel.ymm_boxes(),
                                any_hit,
                                #[inline(always)]
                                |i, hit, block| {
                                    if i % AHEAD == 0 {
                                        ahead(i);
                                    }
                                    let hit = query_hit(hit);
                                    if let Some(normal) = normal_out.get_mut(i) {
                                        normal.write(block_normal(
                                            kernel_ref.scene,
                                            &chunk_rays[i],
                                            &hit,
                                            block,
                                        ));
                                    }
                                    hits[i].write(hit);
                                },
                            )
                        },
                    )
                }
            } else {
                for i in (0..CHUNK).step_by(AHEAD) {
                    ahead(i);
                }
                match (incoherent, large, vector_sort) {
                    (true, true, true) => chunk!(INTERLEAVED_INCOHERENT_RAYS, true, true),
                    (true, true, false) => chunk!(INTERLEAVED_INCOHERENT_RAYS, true, false),
                    (true, false, true) => chunk!(INTERLEAVED_RAYS, false, true),
                    _ => chunk!(INTERLEAVED_RAYS, false, false),
                }
            }
            // SAFETY: trace_chunk wrote every element of both.
            let (hits, normals) = unsafe {
                (
                    &mut *(hits as *mut [_] as *mut [layout::Hit]),
                    &*(normal_out as *const [_] as *const [[f32; 3]]),
                )
            };
            if let Some((_, shifts)) = &moved {
                for (hit, &shift) in hits.iter_mut().zip(shifts) {
                    *hit = crate::placement::world_hit(*hit, shift);
                }
            }
            each(&TracedChunk {
                start,
                hits,
                normals,
                moved: frame == RayFrame::Local && filled == Filled::Moved,
            });
        });
}

/// Whether a query runs its rays in packets (packet.rs): coherent rays
/// (`coherent`, as `trace_rays_each` judges them) through a scene of
/// triangles alone under the watertight test (`Kernel::features` 0),
/// traversing its BVH. Any-hit rays too: a ray whose order of children
/// leaves the packet's is traced again alone (`packet::out_of_order`).
fn packets_apply(kernel: &f32::Kernel, coherent: bool) -> bool {
    coherent
        && kernel.features() == 0
        && kernel.compressed.is_none()
        && kernel.scene.accel.traverses_bvh()
}

/// Whether `trace_rays_with` (through `cpu_kernel`: the packets' choice
/// is the same on every one, and for closest and any hits) traces `rays`
/// in packets: for tests, which check the choice where the packets must
/// not run (spheres, alpha masks, another triangle test, incoherent rays).
pub fn traces_in_packets(scene: &Scene, rays: &[layout::Ray], intersect: Intersect) -> bool {
    let mut kernel = f32::Kernel::new_for(scene, false);
    kernel.intersect = intersect;
    packets_apply(&kernel, coherent(&QueryRays::Slice(rays), nearby(scene)))
}

/// Rays closer than this count as leaving from nearby points (`coherent`).
fn nearby(scene: &Scene) -> f32 {
    scene
        .bvh
        .bounds()
        .map_or(0.0, |b| 0.01 * (b.max - b.min).length())
}

/// Traces `rays` into `hits`, `LANES` rays in turn (`Kernel::visit` with
/// `PREFETCH`, `VECTOR_SORT` and `FEATURES`, which must include the
/// kernel's `features()`).
///
/// # Safety
/// With `VECTOR_SORT`, the CPU must have AVX-512 (f32's `Scalar::has_vector_sort`).
#[inline(always)]
unsafe fn trace_chunk<
    const LANES: usize,
    const PREFETCH: bool,
    const VECTOR_SORT: bool,
    const FEATURES: u8,
>(
    kernel: &f32::Kernel,
    rays: &[layout::Ray],
    hits: &mut [std::mem::MaybeUninit<layout::Hit>],
    normals: &mut [std::mem::MaybeUninit<[f32; 3]>],
    any_hit: bool,
) {
    if rays.is_empty() {
        return;
    }
    if !kernel.scene.accel.traverses_bvh() {
        for (i, (ray, out)) in rays.iter().zip(hits).enumerate() {
            let hit = query_hit(kernel.trace(f32::Ray::from_query(ray), any_hit));
            if let Some(normal) = normals.get_mut(i) {
                normal.write(crate::scene::hit_normal(kernel.scene, ray, &hit));
            }
            out.write(hit);
        }
        return;
    }
    // A function, not a closure, so that it can be inlined: it then runs
    // with the kernel's vector instructions, and builds the traversal in
    // place rather than returning it through memory.
    #[inline(always)]
    fn start(ray: &layout::Ray, any_hit: bool) -> f32::Traversal {
        let (ray, shear) = f32::prepare_ray(f32::Ray::from_query(ray));
        f32::Traversal::new(ray, shear, any_hit)
    }
    // Lane k traces ray index[k] with traversals[k] and stacks[k]; a lane
    // whose ray is done takes the next one.
    let lanes = LANES.min(rays.len());
    let mut stacks: [f32::TraversalStack; LANES] = std::array::from_fn(|_| f32::new_stack());
    let mut index: [usize; LANES] = std::array::from_fn(|k| k);
    let mut traversals: [f32::Traversal; LANES] =
        std::array::from_fn(|k| start(&rays[k.min(rays.len() - 1)], any_hit));
    let mut next = lanes;
    let mut active = lanes;
    while active > 0 {
        for k in 0..lanes {
            // SAFETY: lane k's traversal is always visited with stacks[k];
            // a new traversal starts with nothing pushed; the caller
            // vouches for VECTOR_SORT.
            if index[k] == usize::MAX
                || unsafe {
                    kernel.visit::<PREFETCH, VECTOR_SORT, FEATURES>(
                        &mut traversals[k],
                        &mut stacks[k],
                    )
                }
            {
                continue;
            }
            let hit = query_hit(traversals[k].answer());
            if let Some(normal) = normals.get_mut(index[k]) {
                normal.write(block_normal(
                    kernel.scene,
                    &rays[index[k]],
                    &hit,
                    traversals[k].hit_block,
                ));
            }
            hits[index[k]].write(hit);
            if next < rays.len() {
                index[k] = next;
                traversals[k] = start(&rays[next], any_hit);
                next += 1;
            } else {
                index[k] = usize::MAX;
                active -= 1;
            }
        }
    }
}

/// `scene::hit_normal`, bit for bit, from the vertices' copies in the leaf
/// block that holds the hit (the kernel has just read it: the triangle
/// array's record would be a miss in cache).
#[inline(always)]
fn block_normal(scene: &Scene, ray: &layout::Ray, hit: &layout::Hit, block: u32) -> [f32; 3] {
    use glam::Vec3;
    if hit.prim == NO_HIT {
        return [0.0; 3];
    }
    // The lane found without a branch a lane: which lane holds the hit
    // is unpredictable, and a search mispredicted nearly every hit.
    let lane = |block: &layout::PrimBlock| {
        let lanes = glam::UVec4::from(block.prims).cmpeq(glam::UVec4::splat(hit.prim));
        (lanes.bitmask() != 0).then(|| lanes.bitmask().trailing_zeros() as usize)
    };
    if let Some(block) = scene.bvh.blocks.get(block as usize)
        && (hit.prim as usize) < scene.triangles.len()
        && let Some(lane) = lane(block)
    {
        let vertex = |k: usize| {
            Vec3::new(
                block.v[k][0][lane],
                block.v[k][1][lane],
                block.v[k][2][lane],
            )
        };
        let v0 = vertex(0);
        return (vertex(1) - v0).cross(vertex(2) - v0).to_array();
    }
    crate::scene::hit_normal(scene, ray, hit)
}

/// A ray query's answer from the kernel's hit: misses as `Hit::MISS`.
#[inline(always)]
fn query_hit(hit: f32::Hit) -> layout::Hit {
    if hit.prim == NO_HIT {
        layout::Hit::MISS
    } else {
        layout::Hit {
            t: hit.t,
            prim: hit.prim,
            u: hit.u,
            v: hit.v,
        }
    }
}

/// The same query in double precision: the oracle. Misses have t = +inf.
/// The rays are in world coordinates.
pub fn trace_rays_f64(scene: &Scene, rays: &[layout::Ray], any_hit: bool) -> Vec<f64::Hit> {
    let kernel = f64::Kernel::new(scene);
    let placement = scene.placement();
    let miss = f64::Hit {
        t: ::core::primitive::f64::INFINITY,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
    };
    rays.par_iter()
        .with_min_len(1024)
        .map(|ray| {
            // In the scene's frame and near its geometry, as the f32 paths
            // trace it, but in f64 throughout (`Placement::place`).
            let ray = f64::Ray::from_query(ray);
            let Some((origin, tmin, tmax, shift)) =
                placement.place(ray.origin, ray.dir, ray.tmin, ray.tmax)
            else {
                return miss;
            };
            let local = f64::Ray {
                origin,
                tmin,
                tmax,
                ..ray
            };
            // SAFETY: the active kernel runs on this CPU.
            let hit = unsafe {
                with_simd(
                    CpuKernel::active(),
                    #[inline(always)]
                    || kernel.trace(local, any_hit),
                )
            };
            if hit.prim == NO_HIT {
                miss
            } else {
                f64::Hit {
                    t: hit.t + shift,
                    ..hit
                }
            }
        })
        .collect()
}

/// Whether most neighbouring rays leave from nearby points (closer than
/// `nearby`) in nearly the same direction (within about 8°), as camera rays
/// and the shadow rays of their hits do: their traversals then share the
/// nodes they load. Looks at 256 pairs spread over the rays.
fn coherent(rays: &QueryRays, nearby: f32) -> bool {
    const PAIRS: usize = 256;
    let step = (rays.len() / PAIRS).max(1);
    let (mut pairs, mut similar) = (0, 0);
    for i in (0..rays.len().saturating_sub(1)).step_by(step) {
        let (a, b) = (rays.ray(i), rays.ray(i + 1));
        let (da, db) = (glam::Vec3::from(a.dir), glam::Vec3::from(b.dir));
        let gap = glam::Vec3::from(a.origin) - glam::Vec3::from(b.origin);
        let cos = da.dot(db);
        // cos > 0.99·|da||db|, without the square roots.
        let aligned = cos > 0.0 && cos * cos > 0.9801 * da.length_squared() * db.length_squared();
        pairs += 1;
        similar += (aligned && gap.length_squared() <= nearby * nearby) as usize;
    }
    2 * similar >= pairs
}
