//! How a scene's primitives go into acceleration structures (no wgpu
//! here, so the layout is tested without a GPU): runs of consecutive
//! primitive ids as the geometries of BLASes, each BLAS one instance of
//! the TLAS, and the table the shader maps a hit back to its primitive id
//! by (`hardware_runs`, shaders/hardware_trace.wgsl).
//!
//! The scene is flattened when it is loaded (each mesh placed in the
//! scene's frame, no instancing), so its triangles go into one BLAS (more
//! only where they exceed the adapter's primitives per BLAS): separate
//! BLASes per mesh would overlap in space, and a ray would descend into
//! each one its path crosses. Within it, each run of consecutive triangles
//! of one opacity is a geometry of its own, since opacity is a geometry's
//! flag: a scene's meshes and materials are runs of ids, so an alpha-masked
//! mesh is a non-opaque geometry and every other triangle stays opaque,
//! decided in the hardware. The spheres are a BLAS of boxes, and so are
//! the triangles where the driver's own triangle and box tests leak
//! (`TriangleGeometry::Boxes`: one run of boxes, each tested by the shader).

/// The adapter's limits a plan keeps to (wgpu's `Limits`).
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    pub blas_primitives: u32,
    pub blas_geometries: u32,
    pub instances: u32,
}

/// Consecutive primitives, one geometry of a BLAS: ids `first ..
/// first + count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    pub first: u32,
    pub count: u32,
    /// Decided in the hardware (no candidate reaches the shader).
    pub opaque: bool,
}

/// What a BLAS holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Triangles,
    /// Each triangle's box (procedural geometry: the shader tests the
    /// triangle).
    TriangleBoxes,
    /// Each sphere's box (procedural geometry: the shader tests the sphere).
    Spheres,
}

/// One BLAS, and the TLAS instance of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlasPlan {
    pub kind: Kind,
    /// Its geometries, in order.
    pub runs: Vec<Run>,
    /// The instance's custom index: where its runs start in `run_bases`.
    pub first_run: u32,
}

/// The scene's acceleration structures, planned.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    pub blases: Vec<BlasPlan>,
    /// Each run's first primitive id, BLAS by BLAS (`hardware_runs`).
    pub run_bases: Vec<u32>,
}

/// An instance's custom index has 24 bits (Vulkan's and wgpu's).
const MAX_CUSTOM_INDEX: u32 = (1 << 24) - 1;

/// Plans `masked.len()` triangles (`masked[i]`: triangle i is alpha-masked,
/// so not opaque), as boxes with `triangle_boxes`, and `spheres` spheres
/// within `limits`; or why they do not fit.
pub fn plan(
    masked: &[bool],
    triangle_boxes: bool,
    spheres: u32,
    limits: Limits,
) -> Result<Plan, String> {
    let mut triangle_runs = Vec::new();
    let mut first = 0;
    for (i, &m) in masked.iter().enumerate() {
        // Boxes reach the shader whatever their flag: one run of them all.
        let last = i + 1 == masked.len();
        if last || (!triangle_boxes && masked[i + 1] != m) {
            let end = i as u32 + 1;
            triangle_runs.push(Run {
                first,
                count: end - first,
                opaque: !m && !triangle_boxes,
            });
            first = end;
        }
    }
    let triangle_kind = match triangle_boxes {
        true => Kind::TriangleBoxes,
        false => Kind::Triangles,
    };
    let sphere_runs = (spheres > 0).then_some(Run {
        first: masked.len() as u32,
        count: spheres,
        opaque: false,
    });
    let mut plan = Plan {
        blases: Vec::new(),
        run_bases: Vec::new(),
    };
    plan.add(triangle_kind, triangle_runs, limits)?;
    plan.add(Kind::Spheres, sphere_runs.into_iter().collect(), limits)?;
    if plan.blases.len() as u64 > limits.instances as u64 {
        return Err(format!(
            "{} acceleration structures, over the adapter's {} instances",
            plan.blases.len(),
            limits.instances
        ));
    }
    Ok(plan)
}

impl Plan {
    /// Adds `runs` of `kind` as BLASes, each with at most the adapter's
    /// primitives and geometries (a longer run split).
    fn add(&mut self, kind: Kind, runs: Vec<Run>, limits: Limits) -> Result<(), String> {
        let max_primitives = limits.blas_primitives.max(1);
        let max_geometries = limits.blas_geometries.max(1) as usize;
        let mut current: Vec<Run> = Vec::new();
        let mut primitives = 0u32;
        for run in runs {
            let mut rest = run;
            while rest.count > 0 {
                if primitives == max_primitives || current.len() == max_geometries {
                    self.push(kind, std::mem::take(&mut current))?;
                    primitives = 0;
                }
                let count = rest.count.min(max_primitives - primitives);
                current.push(Run { count, ..rest });
                primitives += count;
                rest.first += count;
                rest.count -= count;
            }
        }
        if !current.is_empty() {
            self.push(kind, current)?;
        }
        Ok(())
    }

    fn push(&mut self, kind: Kind, runs: Vec<Run>) -> Result<(), String> {
        let first_run = self.run_bases.len() as u32;
        if first_run > MAX_CUSTOM_INDEX {
            return Err(format!(
                "more than {MAX_CUSTOM_INDEX} runs of primitives of one opacity"
            ));
        }
        self.run_bases.extend(runs.iter().map(|r| r.first));
        self.blases.push(BlasPlan {
            kind,
            runs,
            first_run,
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WIDE: Limits = Limits {
        blas_primitives: 1 << 24,
        blas_geometries: 1 << 24,
        instances: 1 << 24,
    };

    fn run(first: u32, count: u32, opaque: bool) -> Run {
        Run {
            first,
            count,
            opaque,
        }
    }

    #[test]
    fn opaque_triangles_are_one_geometry_and_spheres_a_blas() {
        let plan = plan(&[false; 5], false, 2, WIDE).unwrap();
        assert_eq!(plan.blases.len(), 2);
        assert_eq!(plan.blases[0].runs, [run(0, 5, true)]);
        assert_eq!(plan.blases[1].kind, Kind::Spheres);
        assert_eq!(plan.blases[1].runs, [run(5, 2, false)]);
        assert_eq!(plan.run_bases, [0, 5]);
        assert_eq!(plan.blases[1].first_run, 1);
    }

    #[test]
    fn masked_runs_are_geometries_of_their_own() {
        let masked = [false, false, true, true, false];
        let plan = plan(&masked, false, 0, WIDE).unwrap();
        assert_eq!(plan.blases.len(), 1);
        let runs = [run(0, 2, true), run(2, 2, false), run(4, 1, true)];
        assert_eq!(plan.blases[0].runs, runs);
        assert_eq!(plan.run_bases, [0, 2, 4]);
    }

    #[test]
    fn triangles_as_boxes_are_one_run_whatever_their_masks() {
        let masked = [false, true, true, false];
        let plan = plan(&masked, true, 1, WIDE).unwrap();
        assert_eq!(plan.blases[0].kind, Kind::TriangleBoxes);
        assert_eq!(plan.blases[0].runs, [run(0, 4, false)]);
        assert_eq!(plan.run_bases, [0, 4]);
    }

    #[test]
    fn limits_split_runs_and_blases() {
        let limits = Limits {
            blas_primitives: 3,
            blas_geometries: 2,
            ..WIDE
        };
        let masked = [false, false, false, false, true, false, false];
        let plan = plan(&masked, false, 4, limits).unwrap();
        let runs: Vec<Vec<Run>> = plan.blases.iter().map(|b| b.runs.clone()).collect();
        assert_eq!(
            runs,
            [
                vec![run(0, 3, true)],
                vec![run(3, 1, true), run(4, 1, false)],
                vec![run(5, 2, true)],
                vec![run(7, 3, false)],
                vec![run(10, 1, false)],
            ]
        );
        // Every primitive once, each run's base its first id.
        let firsts: Vec<u32> = runs.iter().flatten().map(|r| r.first).collect();
        assert_eq!(plan.run_bases, firsts);
        let covered: u32 = runs.iter().flatten().map(|r| r.count).sum();
        assert_eq!(covered, 11);
    }

    #[test]
    fn too_many_instances_is_an_error_that_says_so() {
        let limits = Limits {
            blas_primitives: 1,
            instances: 2,
            ..WIDE
        };
        let e = plan(&[false; 3], false, 0, limits).unwrap_err();
        assert!(e.contains("over the adapter's 2 instances"), "{e}");
    }

    #[test]
    fn an_empty_scene_has_no_blas() {
        let plan = plan(&[], false, 0, WIDE).unwrap();
        assert!(plan.blases.is_empty());
    }
}
