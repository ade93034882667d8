//! The CPU reference path: the shader's algorithm in Rust, run in parallel
//! with rayon. `f32` is the reference the GPU is diffed against; `f64` is the
//! same code in double precision, the oracle that measures both.

use rayon::prelude::*;

use crate::layout::{self, NO_HIT};
use crate::output::{Image, Rendered};
use crate::progress::Progress;
use crate::scene::{Accel, Intersect, Scene};

/// Single precision, as on the GPU.
#[allow(clippy::unnecessary_cast)]
pub mod f32 {
    pub type Real = f32;
    pub type Vec3 = glam::Vec3;
    pub type Vec4 = glam::Vec4;

    /// `a` where a > b, else `b` (a NaN in either yields `b`): the shader's
    /// `select(b, a, a > b)`, in one instruction where SSE's maxps and
    /// minps give exactly that (their second operand unless the comparison
    /// holds).
    #[inline(always)]
    fn greater_of(a: Vec4, b: Vec4) -> Vec4 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE is part of x86_64.
        return Vec4::from(unsafe { std::arch::x86_64::_mm_max_ps(a.into(), b.into()) });
        #[cfg(not(target_arch = "x86_64"))]
        return Vec4::select(a.cmpgt(b), a, b);
    }

    /// `a` where a < b, else `b` (a NaN in either yields `b`).
    #[inline(always)]
    fn lesser_of(a: Vec4, b: Vec4) -> Vec4 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE is part of x86_64.
        return Vec4::from(unsafe { std::arch::x86_64::_mm_min_ps(a.into(), b.into()) });
        #[cfg(not(target_arch = "x86_64"))]
        return Vec4::select(a.cmplt(b), a, b);
    }

    /// Whether this process runs `intersect_boxes_ymm`.
    pub fn has_ymm_boxes() -> bool {
        super::CpuKernel::active().ymm_boxes()
    }

    /// `intersect_boxes` with each row of eight planes in one AVX register:
    /// the same IEEE operations lane for lane (maxps and minps are
    /// `greater_of` and `lesser_of`), so the same result, in half the
    /// instructions of two 4-lane halves.
    ///
    /// Inlined into `with_simd`'s kernels, which every entry point of the
    /// CPU path runs in. (Compiled for its own features instead, it was 4%
    /// slower there; a caller outside them, as tests are, runs each
    /// intrinsic as a call: the same result, slowly.)
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA (`has_ymm_boxes`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub unsafe fn intersect_boxes_ymm(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
        use std::arch::x86_64::*;
        // SAFETY: the caller vouches for AVX and FMA; a node is 64-byte
        // aligned, so each 32-byte row is too.
        unsafe {
            let mut t_near = _mm256_set1_ps(ray.tmin);
            let mut t_far = _mm256_set1_ps(ray.tmax);
            for axis in 0..3 {
                let flip = slabs.flip[axis] as usize;
                let near_plane = _mm256_load_ps(node.bounds[2 * axis + flip].as_ptr());
                let far_plane = _mm256_load_ps(node.bounds[2 * axis + 1 - flip].as_ptr());
                let near = _mm256_fmadd_ps(
                    near_plane,
                    _mm256_set1_ps(slabs.inv_dir[axis]),
                    _mm256_set1_ps(slabs.near_offset[axis]),
                );
                let far = _mm256_fmadd_ps(
                    far_plane,
                    _mm256_set1_ps(slabs.inv_dir_far[axis]),
                    _mm256_set1_ps(slabs.far_offset[axis]),
                );
                t_near = _mm256_max_ps(near, t_near);
                t_far = _mm256_min_ps(far, t_far);
            }
            let inside = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t_near, _mm256_set1_ps(ray.tmax)),
            );
            let mut t = [0.0; BVH_WIDTH];
            _mm256_storeu_ps(t.as_mut_ptr(), t_near);
            BoxHits {
                t,
                entered: _mm256_movemask_ps(inside) as u32,
            }
        }
    }

    /// `visit`'s ordering of the entered children (`entered`, one or more),
    /// in vector registers and without the data-dependent branches of
    /// `visit` and `push_sorted`, which on incoherent rays mispredict about
    /// as often as not. Pushes them farthest deepest, lower slots deeper
    /// among equal distances (exactly the order of `visit`: with two, the
    /// nearer, the second on a tie, is visited; with more, `push_sorted`'s),
    /// pops the nearest and returns it.
    ///
    /// Each child's depth on the stack is the number of entered children
    /// whose key (distance, then slot) is greater than its own, counted in
    /// one register of eight 64-bit keys against its seven rotations; one
    /// masked scatter then writes every entry at its depth.
    ///
    /// # Safety
    /// The CPU must have AVX-512 (`has_vector_sort`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(crate) unsafe fn push_sorted_zmm(
        stack: &mut TraversalStack,
        sp: &mut usize,
        t: &[Real; BVH_WIDTH],
        children: &[u32; BVH_WIDTH],
        entered: u32,
    ) -> u32 {
        use std::arch::x86_64::*;
        type Entry = (u32, Real);
        // Where a stack entry's two halves are, as shifts within a 64-bit
        // lane (a tuple's layout is the compiler's choice).
        const CHILD_SHIFT: u64 = 8 * std::mem::offset_of!(Entry, 0) as u64;
        const T_SHIFT: u64 = 8 * std::mem::offset_of!(Entry, 1) as u64;
        const { assert!(std::mem::size_of::<Entry>() == 8) };
        let count = entered.count_ones() as usize;
        // The insertion's bounds checks, in one.
        assert!(*sp + count <= STACK_SIZE);
        let lanes = entered as __mmask8;
        // SAFETY: the caller vouches for AVX-512; the scatter writes entries
        // sp..sp + count, inside the stack (asserted).
        unsafe {
            let t_bits = _mm256_loadu_si256(t.as_ptr().cast());
            // Distances as unsigned integers in the same order: −0 made +0
            // (they compare equal), then all bits of a negative float
            // flipped, only the sign bit of a positive one.
            let canonical = _mm256_castps_si256(_mm256_add_ps(
                _mm256_castsi256_ps(t_bits),
                _mm256_setzero_ps(),
            ));
            let flip = _mm256_or_si256(
                _mm256_srai_epi32::<31>(canonical),
                _mm256_set1_epi32(i32::MIN),
            );
            let ordered = _mm256_xor_si256(canonical, flip);
            // Key: distance above, 7 − slot below (lower slots deeper on a
            // tie); 0 in lanes not entered, below every entered key.
            let keys = _mm512_maskz_or_epi64(
                lanes,
                _mm512_slli_epi64::<32>(_mm512_cvtepu32_epi64(ordered)),
                _mm512_set_epi64(0, 1, 2, 3, 4, 5, 6, 7),
            );
            let one = _mm512_set1_epi64(1);
            let mut depth = _mm512_setzero_si512();
            macro_rules! count_greater {
                ($($rotation:literal)*) => {$(
                    let rotated = _mm512_alignr_epi64::<$rotation>(keys, keys);
                    let greater = _mm512_cmpgt_epu64_mask(rotated, keys);
                    depth = _mm512_mask_add_epi64(depth, greater, depth, one);
                )*};
            }
            count_greater!(1 2 3 4 5 6 7);
            let entries = _mm512_or_si512(
                _mm512_sll_epi64(
                    _mm512_cvtepu32_epi64(_mm256_loadu_si256(children.as_ptr().cast())),
                    _mm_cvtsi64_si128(CHILD_SHIFT as i64),
                ),
                _mm512_sll_epi64(
                    _mm512_cvtepu32_epi64(t_bits),
                    _mm_cvtsi64_si128(T_SHIFT as i64),
                ),
            );
            _mm512_mask_i64scatter_epi64::<8>(
                stack.as_mut_ptr().add(*sp).cast(),
                lanes,
                depth,
                entries,
            );
            let nearest =
                _mm512_mask_cmpeq_epi64_mask(lanes, depth, _mm512_set1_epi64(count as i64 - 1));
            *sp += count - 1;
            children[nearest.trailing_zeros() as usize]
        }
    }

    /// Whether this process runs `push_sorted_zmm`.
    pub fn has_vector_sort() -> bool {
        super::CpuKernel::active().vector_sort()
    }

    #[cfg(not(target_arch = "x86_64"))]
    pub(crate) use super::no_push_sorted_zmm as push_sorted_zmm;

    /// No 8-lane registers here: `has_ymm_boxes` is false, so this never runs.
    ///
    /// # Safety
    /// None needed: unsafe only as the x86 version is.
    #[cfg(not(target_arch = "x86_64"))]
    pub unsafe fn intersect_boxes_ymm(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
        intersect_boxes(ray, slabs, node)
    }

    /// `x` with the low 12 of its 23 stored mantissa bits cleared: a 12-bit
    /// high half whose square and product with the rest (`x − high_half`,
    /// 12 bits) are exact in f32 (Dekker's split, by mask rather than by
    /// the multiply of Veltkamp's, which a fused multiply-add would spoil).
    #[inline(always)]
    fn high_half(x: Real) -> Real {
        Real::from_bits(x.to_bits() & 0xffff_f000)
    }

    include!("kernel.rs");
}

/// Double precision: the oracle.
#[allow(clippy::unnecessary_cast)]
pub mod f64 {
    pub type Real = f64;
    pub type Vec3 = glam::DVec3;
    pub type Vec4 = glam::DVec4;

    /// `a` where a > b, else `b` (a NaN in either yields `b`).
    #[inline(always)]
    fn greater_of(a: Vec4, b: Vec4) -> Vec4 {
        Vec4::select(a.cmpgt(b), a, b)
    }

    /// `a` where a < b, else `b` (a NaN in either yields `b`).
    #[inline(always)]
    fn lesser_of(a: Vec4, b: Vec4) -> Vec4 {
        Vec4::select(a.cmplt(b), a, b)
    }

    /// The oracle takes the portable `intersect_boxes` everywhere.
    pub fn has_ymm_boxes() -> bool {
        false
    }

    use super::no_push_sorted_zmm as push_sorted_zmm;

    /// Never runs (`has_ymm_boxes` is false).
    ///
    /// # Safety
    /// None needed: unsafe only as its single-precision twin is.
    pub unsafe fn intersect_boxes_ymm(ray: &Ray, slabs: &Slabs, node: &BvhNode) -> BoxHits {
        intersect_boxes(ray, slabs, node)
    }

    /// `x` with the low 26 of its 52 stored mantissa bits cleared: the
    /// oracle's twin of the f32 split (27 and 26 bits, each product exact).
    #[inline(always)]
    fn high_half(x: Real) -> Real {
        Real::from_bits(x.to_bits() & !((1u64 << 26) - 1))
    }

    include!("kernel.rs");
}

/// `push_sorted_zmm` where there is none (the oracle; CPUs other than x86):
/// never called, since only `trace_rays` asks for it, in single precision
/// and where `f32::has_vector_sort` says the CPU has AVX-512.
///
/// # Safety
/// None needed: unsafe only as `f32::push_sorted_zmm` is.
pub(crate) unsafe fn no_push_sorted_zmm<Stack, Distances>(
    _stack: &mut Stack,
    _sp: &mut usize,
    _t: &Distances,
    _children: &[u32; crate::layout::BVH_WIDTH],
    _entered: u32,
) -> u32 {
    unreachable!("push_sorted_zmm needs AVX-512 and single precision")
}

/// Which precision the CPU path computes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    F32,
    F64,
}

/// One pixel in the chosen precision: colour, first primitive, variance of
/// the mean luminance.
#[inline(always)]
fn pixel(
    kernel32: &f32::Kernel,
    kernel64: &f64::Kernel,
    precision: Precision,
    x: u32,
    y: u32,
) -> ([::core::primitive::f32; 3], u32, ::core::primitive::f32) {
    match precision {
        Precision::F32 => {
            let (c, p, v) = kernel32.render_pixel(x, y);
            (c.to_array(), p, v)
        }
        Precision::F64 => {
            let (c, p, v) = kernel64.render_pixel(x, y);
            (c.as_vec3().to_array(), p, v as ::core::primitive::f32)
        }
    }
}

/// Renders every pixel with the scene's samples; rows run in parallel.
pub fn render(scene: &Scene, precision: Precision, progress: &Progress) -> Rendered {
    render_with(scene, precision, progress, CpuKernel::active())
}

/// Panics unless this CPU runs `kernel`: what makes `with_simd` safe for
/// the `_with` entry points.
fn check_runs(kernel: CpuKernel) {
    if let Some(missing) = kernel.missing() {
        panic!("the {} CPU kernel needs {missing}", kernel.name());
    }
}

/// Renders rows `rows` of the scene's image alone (a part of it).
pub fn render_rows(
    scene: &Scene,
    precision: Precision,
    rows: std::ops::Range<u32>,
    progress: &Progress,
) -> Rendered {
    render_rows_with(scene, precision, rows, progress, CpuKernel::active(), None)
}

/// `render` with a given CPU kernel (one this CPU runs).
pub fn render_with(
    scene: &Scene,
    precision: Precision,
    progress: &Progress,
    cpu_kernel: CpuKernel,
) -> Rendered {
    render_rows_with(
        scene,
        precision,
        0..scene.camera.height,
        progress,
        cpu_kernel,
        None,
    )
}

/// The GPU's twin: renders in single precision tracing the GPU's
/// compressed BVH as the shader does (`f32::Kernel::trace_compressed`), so
/// that a GPU/CPU difference is one of arithmetic, never of traversal
/// order. What `lambert diff` and the tests compare the GPU with.
pub fn render_gpu_twin(scene: &Scene, progress: &Progress) -> Rendered {
    let nodes = crate::cwbvh::compress(&scene.bvh);
    render_rows_with(
        scene,
        Precision::F32,
        0..scene.camera.height,
        progress,
        CpuKernel::Portable,
        Some(&nodes),
    )
}

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

/// The twin's short stack: a WebGPU device's (the GPU's own where its
/// workgroup memory is the minimum), spilling where the GPU's would.
fn twin_stack_entries(scene: &Scene) -> usize {
    crate::cwbvh::short_stack(scene.bvh.depth(), crate::cwbvh::MIN_WORKGROUP_BYTES).0
}

fn render_rows_with(
    scene: &Scene,
    precision: Precision,
    rows: std::ops::Range<u32>,
    progress: &Progress,
    cpu_kernel: CpuKernel,
    compressed: Option<&[layout::CompressedNode]>,
) -> Rendered {
    check_runs(cpu_kernel);
    let first_row = rows.start as usize;
    let (width, height) = (scene.camera.width as usize, rows.len());
    let mut rgb = vec![[0.0; 3]; width * height];
    let mut prims = vec![0u32; width * height];
    let mut variance = vec![0.0; width * height];
    let mut kernel32 = f32::Kernel::new_for(scene, cpu_kernel.ymm_boxes());
    kernel32.compressed = compressed;
    kernel32.stack_entries = twin_stack_entries(scene);
    let kernel64 = f64::Kernel::new(scene);
    rgb.par_chunks_mut(width)
        .zip(prims.par_chunks_mut(width))
        .zip(variance.par_chunks_mut(width))
        .enumerate()
        .for_each(|(row, ((rgb_row, prim_row), variance_row))| {
            let y = first_row + row;
            // SAFETY: checked above.
            unsafe {
                with_simd(
                    cpu_kernel,
                    #[inline(always)]
                    || {
                        for x in 0..width {
                            let (c, p, v) =
                                pixel(&kernel32, &kernel64, precision, x as u32, y as u32);
                            rgb_row[x] = c;
                            prim_row[x] = p;
                            variance_row[x] = v;
                        }
                    },
                )
            };
            progress.inc(1);
        });
    Rendered {
        image: Image {
            width: width as u32,
            height: height as u32,
            rgb,
        },
        prims,
        variance,
    }
}

/// Renders the listed pixels only (adaptive sampling's later passes):
/// mean colour and variance of the mean, as `render_pixel_list` on the GPU.
pub fn render_pixel_list(scene: &Scene, pixels: &[[u32; 2]]) -> Vec<[::core::primitive::f32; 4]> {
    let kernel32 = f32::Kernel::new(scene);
    let kernel64 = f64::Kernel::new(scene);
    pixels
        .par_iter()
        .map(|&[x, y]| {
            // SAFETY: the active kernel runs on this CPU.
            let (c, _, v) = unsafe {
                with_simd(
                    CpuKernel::active(),
                    #[inline(always)]
                    || pixel(&kernel32, &kernel64, Precision::F32, x, y),
                )
            };
            [c[0], c[1], c[2], v]
        })
        .collect()
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
    // Written by the threads themselves: filling it first on one thread
    // would cost a twentieth of the trace.
    let mut hits: Vec<layout::Hit> = Vec::with_capacity(rays.len());
    let out = SharedOut(hits.as_mut_ptr());
    trace_rays_each(
        scene,
        QueryRays::Slice(rays),
        QueryOptions {
            any_hit,
            intersect,
            cpu_kernel,
            normals: false,
        },
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
/// before the trace, nor a buffer of them).
#[derive(Clone, Copy)]
pub enum QueryRays<'a> {
    Slice(&'a [layout::Ray]),
    Fill(
        usize,
        &'a (dyn Fn(usize, &mut [std::mem::MaybeUninit<layout::Ray>]) + Sync),
    ),
}

impl QueryRays<'_> {
    pub fn len(&self) -> usize {
        match self {
            QueryRays::Slice(rays) => rays.len(),
            QueryRays::Fill(count, _) => *count,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Ray `i`.
    pub fn ray(&self, i: usize) -> layout::Ray {
        match self {
            QueryRays::Slice(rays) => rays[i],
            QueryRays::Fill(_, fill) => {
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
    /// Each hit's geometric normal too (`rays::hit_normal`'s, bit for bit),
    /// taken from the leaf block the kernel just read.
    pub normals: bool,
}

/// A traced chunk of a query: its first ray's index, its rays' hits and,
/// when asked for, their normals (else empty).
pub struct TracedChunk<'a> {
    pub start: usize,
    pub hits: &'a [layout::Hit],
    pub normals: &'a [[f32; 3]],
}

/// Traces `rays` in parallel chunks, handing each chunk's hits (with the
/// index of its first ray) to `each` while they are hot in cache: the
/// Python binding fills its numpy columns this way, with no hit buffer
/// between. The rays are in world coordinates (as in a ray file): each is
/// moved into the scene's frame (`Placement::local_ray`), and its hit back.
pub fn trace_rays_each(
    scene: &Scene,
    rays: QueryRays,
    options: QueryOptions,
    each: &(dyn Fn(&TracedChunk) + Sync),
) {
    trace_rays_each_in(scene, rays, options, true, each)
}

/// `trace_rays_each` for rays already in the scene's frame (from
/// `Placement::local_ray`, say, for rays given in f64), hits in that frame.
pub fn trace_local_rays_each(
    scene: &Scene,
    rays: QueryRays,
    options: QueryOptions,
    each: &(dyn Fn(&TracedChunk) + Sync),
) {
    trace_rays_each_in(scene, rays, options, false, each)
}

fn trace_rays_each_in(
    scene: &Scene,
    rays: QueryRays,
    options: QueryOptions,
    world: bool,
    // Not generic: a generic would be compiled in the caller's crate, with
    // its codegen settings, and the kernel ran up to 40% slower there.
    each: &(dyn Fn(&TracedChunk) + Sync),
) {
    use std::mem::MaybeUninit;
    const CHUNK: usize = 1024;
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
    // Rays closer than this count as leaving from nearby points.
    let nearby = scene
        .bvh
        .bounds()
        .map_or(0.0, |b| 0.01 * (b.max - b.min).length());
    // Judged once for the whole query: judged per chunk, it cost camera
    // rays through small models up to 5%.
    let incoherent = (large || vector_sort) && !coherent(&rays, nearby);
    (0..rays.len().div_ceil(CHUNK))
        .into_par_iter()
        .for_each(|index| {
            let start = index * CHUNK;
            let len = CHUNK.min(rays.len() - start);
            let mut own = [MaybeUninit::<layout::Ray>::uninit(); CHUNK];
            let chunk_rays = match rays {
                QueryRays::Slice(all) => &all[start..start + len],
                QueryRays::Fill(_, fill) => {
                    fill(start, &mut own[..len]);
                    // SAFETY: `fill` writes all of its buffer.
                    unsafe { &*(&own[..len] as *const [_] as *const [layout::Ray]) }
                }
            };
            let mut local = [layout::Ray::default(); CHUNK];
            let mut shifts = [0.0; CHUNK];
            let moved =
                world && placement.localize_into(chunk_rays, &mut local[..len], &mut shifts[..len]);
            let chunk_rays = if moved { &local[..len] } else { chunk_rays };
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
                    // SAFETY: the kernel was checked; VECTOR_SORT only
                    // where `vector_sort` says the CPU can.
                    unsafe {
                        with_simd(
                            cpu_kernel,
                            #[inline(always)]
                            || {
                                trace_chunk::<{ $lanes }, $prefetch, $vector_sort>(
                                    &kernel, chunk_rays, hits, normal_out, any_hit,
                                )
                            },
                        )
                    }
                };
            }
            match (incoherent, large, vector_sort) {
                (true, true, true) => chunk!(INTERLEAVED_INCOHERENT_RAYS, true, true),
                (true, true, false) => chunk!(INTERLEAVED_INCOHERENT_RAYS, true, false),
                (true, false, true) => chunk!(INTERLEAVED_RAYS, false, true),
                _ => chunk!(INTERLEAVED_RAYS, false, false),
            }
            // SAFETY: trace_chunk wrote every element of both.
            let (hits, normals) = unsafe {
                (
                    &mut *(hits as *mut [_] as *mut [layout::Hit]),
                    &*(normal_out as *const [_] as *const [[f32; 3]]),
                )
            };
            if moved {
                for (hit, &shift) in hits.iter_mut().zip(&shifts[..len]) {
                    *hit = crate::placement::world_hit(*hit, shift);
                }
            }
            each(&TracedChunk {
                start,
                hits,
                normals,
            });
        });
}

/// The CPU kernels: the same functions compiled for different vector
/// instructions. Each runs the same IEEE operations, so each gives the
/// portable kernel's results bit for bit (tests/cpu_kernels.rs checks that
/// on every kernel the test machine can run).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum CpuKernel {
    /// Plain Rust (SSE2 on x86-64; NEON or none elsewhere).
    Portable,
    /// AVX2 with FMA (x86 since 2013): the 8-lane slab test in one
    /// register, and fused multiply-adds (without FMA, each is a library
    /// call per lane: about 4× slower traversal).
    Avx2Fma,
    /// AVX-512 (F, VL, DQ, BW, with BMI1/2 and LZCNT): AVX2's kernel with
    /// mask registers and embedded broadcasts, and incoherent rays order
    /// their entered children in vector registers (`push_sorted_zmm`).
    Avx512,
}

impl CpuKernel {
    pub const ALL: [CpuKernel; 3] = [CpuKernel::Portable, CpuKernel::Avx2Fma, CpuKernel::Avx512];

    /// The name `LAMBERT_CPU_KERNEL` and `lambert info` use.
    pub fn name(self) -> &'static str {
        match self {
            CpuKernel::Portable => "portable",
            CpuKernel::Avx2Fma => "avx2+fma",
            CpuKernel::Avx512 => "avx-512",
        }
    }

    /// What this CPU lacks for the kernel, or None when it can run it.
    pub fn missing(self) -> Option<&'static str> {
        #[cfg(target_arch = "x86_64")]
        {
            use std::is_x86_feature_detected as has;
            let avx2_fma = has!("avx2") && has!("fma");
            match self {
                CpuKernel::Portable => None,
                CpuKernel::Avx2Fma => (!avx2_fma).then_some("AVX2 and FMA"),
                CpuKernel::Avx512 => {
                    let avx512 =
                        has!("avx512f") && has!("avx512vl") && has!("avx512dq") && has!("avx512bw");
                    let bits = has!("bmi1") && has!("bmi2") && has!("lzcnt");
                    (!(avx2_fma && avx512 && bits))
                        .then_some("AVX-512 F/VL/DQ/BW with BMI1, BMI2 and LZCNT")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        return match self {
            CpuKernel::Portable => None,
            _ => Some("an x86-64 CPU"),
        };
    }

    /// The widest kernel this CPU runs.
    pub fn detect() -> CpuKernel {
        *CpuKernel::ALL
            .iter()
            .rev()
            .find(|k| k.missing().is_none())
            .unwrap_or(&CpuKernel::Portable)
    }

    /// The kernel this process uses: `detect`'s, or a narrower one named by
    /// `LAMBERT_CPU_KERNEL` (portable, avx2+fma or avx-512; one the CPU
    /// lacks falls back to the widest it has). Decided once.
    pub fn active() -> CpuKernel {
        static ACTIVE: std::sync::OnceLock<CpuKernel> = std::sync::OnceLock::new();
        *ACTIVE.get_or_init(|| {
            let best = CpuKernel::detect();
            std::env::var("LAMBERT_CPU_KERNEL")
                .ok()
                .and_then(|name| {
                    CpuKernel::ALL
                        .into_iter()
                        .find(|k| k.name() == name.to_lowercase())
                })
                .map_or(best, |asked| asked.min(best))
        })
    }

    /// Whether node visits take `f32::intersect_boxes_ymm`.
    pub fn ymm_boxes(self) -> bool {
        self >= CpuKernel::Avx2Fma
    }

    /// Whether incoherent rays order children with `f32::push_sorted_zmm`.
    pub fn vector_sort(self) -> bool {
        self == CpuKernel::Avx512
    }
}

/// Runs `f` (an `#[inline(always)]` closure) compiled for `kernel`'s vector
/// instructions: the kernel's functions are inlined into it, so they run
/// the same IEEE operations (the same results) in fewer instructions.
///
/// # Safety
/// The CPU must run `kernel` (`CpuKernel::missing` is None).
#[inline(always)]
unsafe fn with_simd<R>(kernel: CpuKernel, f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    match kernel {
        CpuKernel::Avx512 => {
            #[target_feature(
                enable = "avx2,fma,avx512f,avx512vl,avx512dq,avx512bw,bmi1,bmi2,lzcnt"
            )]
            fn avx512<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // SAFETY: the caller vouches for the features.
            return unsafe { avx512(f) };
        }
        CpuKernel::Avx2Fma => {
            #[target_feature(enable = "avx2,fma")]
            fn avx2<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // SAFETY: the caller vouches for the features.
            return unsafe { avx2(f) };
        }
        CpuKernel::Portable => {}
    }
    let _ = kernel;
    f()
}

/// Starts loading the cache lines of the `T` at `p` (which may be out of
/// bounds: a prefetch never faults).
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    for line in (0..std::mem::size_of::<T>()).step_by(64) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: prefetching is a hint; it reads nothing.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>().wrapping_add(line)) };
    }
    // Stable Rust has a prefetch intrinsic on x86 only.
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Rays one thread traces together through the BVH, a node visit each in
/// turn, so that one ray's cache misses overlap the others' work. Each ray
/// takes exactly the path it takes alone. Two (docs/benchmarks.md): through
/// the dragon, incoherent rays gain 60% and camera rays 1–2% over one;
/// camera rays through a model that stays in cache lose 17%.
const INTERLEAVED_RAYS: usize = 2;

/// Incoherent rays through a BVH larger than a core's cache wait on memory
/// at nearly every node. Eight in turn, each asking for its next node or
/// leaf as soon as it knows it (`Kernel::visit` with `PREFETCH`), keep
/// many loads in flight: the dragon's 1M random rays trace 1.3× faster
/// with prefetching (four rays either way) and about 1.13× faster again
/// with eight rays instead of four (twelve: +1–2%, noise). Coherent rays, or a
/// BVH that stays in cache, lose to the book-keeping: 3–4% for the
/// prefetches alone on the dragon's camera rays, 8% for both on
/// dragon_res4's random rays (docs/benchmarks.md).
const INTERLEAVED_INCOHERENT_RAYS: usize = 8;

/// BVH nodes and blocks above this size count as larger than a core's cache
/// (L2 is 1–2 MiB a core on current x86 servers). Random rays with eight in
/// turn and prefetching, against two without (both ordering children in
/// vector registers): stanford_bunny's 3.8 MiB BVH gains 7–14%,
/// dragon_res3's 2.7 MiB loses up to 14%. Before that ordering:
/// dragon_res4's 0.6 MiB lost 8%, dragon_res2's 11 MiB gained 6–13%, the
/// dragon's 47 MiB 44%.
pub const LARGE_BVH_BYTES: usize = 3 << 20;

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

/// Traces `rays` into `hits`, `LANES` rays in turn (`Kernel::visit` with
/// `PREFETCH` and `VECTOR_SORT`).
///
/// # Safety
/// With `VECTOR_SORT`, the CPU must have AVX-512 (`f32::has_vector_sort`).
#[inline(always)]
unsafe fn trace_chunk<const LANES: usize, const PREFETCH: bool, const VECTOR_SORT: bool>(
    kernel: &f32::Kernel,
    rays: &[layout::Ray],
    hits: &mut [std::mem::MaybeUninit<layout::Hit>],
    normals: &mut [std::mem::MaybeUninit<[f32; 3]>],
    any_hit: bool,
) {
    if rays.is_empty() {
        return;
    }
    if kernel.scene.accel != Accel::Bvh {
        for (i, (ray, out)) in rays.iter().zip(hits).enumerate() {
            let hit = query_hit(kernel.trace(f32::Ray::from_query(ray), any_hit));
            if let Some(normal) = normals.get_mut(i) {
                normal.write(crate::rays::hit_normal(kernel.scene, ray, &hit));
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
                    kernel.visit::<PREFETCH, VECTOR_SORT>(&mut traversals[k], &mut stacks[k])
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

/// `rays::hit_normal`, bit for bit, from the vertices' copies in the leaf
/// block that holds the hit (the kernel has just read it: the triangle
/// array's record would be a miss in cache).
#[inline(always)]
fn block_normal(scene: &Scene, ray: &layout::Ray, hit: &layout::Hit, block: u32) -> [f32; 3] {
    use glam::Vec3;
    if let Some(block) = scene.bvh.blocks.get(block as usize)
        && (hit.prim as usize) < scene.triangles.len()
        && let Some(lane) = block.prims.iter().position(|&p| p == hit.prim)
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
    crate::rays::hit_normal(scene, ray, hit)
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

#[cfg(test)]
mod tests {
    use super::f32::{new_stack, push_sorted, push_sorted_zmm};
    use crate::layout::{BVH_WIDTH, LEAF_BIT};

    /// `push_sorted_zmm` pushes exactly what the insertion pushes, in the
    /// same order, and visits the same child, for every set of entered
    /// children (with one or two, the insertion does what `visit`'s own
    /// cases do: visit the one; push the farther, visit the nearer, the
    /// second on a tie), with ties, ±0, negative and huge distances, above
    /// entries already pushed.
    #[test]
    fn vector_child_ordering_equals_the_insertion() {
        if let Some(missing) = super::CpuKernel::Avx512.missing() {
            // Straight to stderr: the harness would hide eprintln! of a
            // passing test.
            use std::io::Write;
            let _ = writeln!(
                std::io::stderr(),
                "skipped: push_sorted_zmm needs {missing}, which this CPU lacks"
            );
            return;
        }
        // Few distinct values, so that ties are common.
        let values = [-1.0, -0.0, 0.0, 0.5, 1.0, 2.5, 1e30, f32::MAX];
        let children: [u32; BVH_WIDTH] = std::array::from_fn(|slot| {
            if slot % 3 == 0 {
                LEAF_BIT | slot as u32
            } else {
                40 + slot as u32
            }
        });
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut checked = 0;
        for entered in 0..1u32 << BVH_WIDTH {
            if entered == 0 {
                continue;
            }
            for _ in 0..64 {
                let t: [f32; BVH_WIDTH] =
                    std::array::from_fn(|_| values[next() as usize % values.len()]);
                let below = (next() % 5) as usize;
                let (mut scalar, mut vector) = (new_stack(), new_stack());
                for i in 0..below {
                    scalar[i].write((i as u32, i as f32));
                    vector[i].write((i as u32, i as f32));
                }
                let (mut sp_scalar, mut sp_vector) = (below, below);
                let nearest = push_sorted(&mut scalar, &mut sp_scalar, &t, &children, entered);
                // SAFETY: the CPU has AVX-512.
                let nearest_vector =
                    unsafe { push_sorted_zmm(&mut vector, &mut sp_vector, &t, &children, entered) };
                assert_eq!(
                    (nearest_vector, sp_vector),
                    (nearest, sp_scalar),
                    "{t:?} {entered:#b}"
                );
                // Every entry up to the popped one, bit for bit.
                for i in 0..=sp_scalar {
                    // SAFETY: written by both (pushed, or the popped nearest).
                    let (a, b) = unsafe { (scalar[i].assume_init(), vector[i].assume_init()) };
                    assert_eq!(
                        (a.0, a.1.to_bits()),
                        (b.0, b.1.to_bits()),
                        "entry {i}: {t:?} {entered:#b}"
                    );
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 255 * 64);
    }
}
