//! `lambert query`: closest points, distances, signed distances and inside
//! tests of a point file, or the crossings of a ray file (docs/ray-query.md,
//! "Closest points, distances and crossings"); its options checked, then
//! the job (`jobs::run_query`) and its report.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, ValueEnum};

use super::options::{AdapterArgs, Device, non_negative};
use super::print_warnings;
use crate::progress_bar;
use lambert::error::{Error, Result};
use lambert::jobs::{PointQuery, QueryJob, QueryKind, RayQuery, Sign, run_query};
use lambert::scene::Scene;

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(super) enum What {
    /// The closest point of the triangles to each point (32-byte records).
    Closest,
    /// The distance to the nearest triangle (f32 per point).
    Distance,
    /// The distance, negative inside (f32 per point).
    SignedDistance,
    /// Whether each point is inside (a byte, 1 or 0, per point).
    Inside,
    /// How many times each ray of --rays crosses the triangles (u32 per ray).
    Count,
    /// Every crossing of each ray of --rays, sorted by ray and t (20-byte records).
    List,
}

/// `--method`: `Sign`.
#[derive(Clone, Copy, ValueEnum)]
pub(super) enum Method {
    /// The generalized winding number, inside where |w| ≥ 0.5 (meshes with holes, either orientation).
    Winding,
    /// The parity of crossings along a ray (watertight meshes).
    Parity,
}

impl From<Method> for Sign {
    fn from(method: Method) -> Sign {
        match method {
            Method::Winding => Sign::Winding,
            Method::Parity => Sign::Parity,
        }
    }
}

#[derive(Args)]
#[command(group = clap::ArgGroup::new("geometry").required(true).args(["scene", "obj"]))]
pub(super) struct QueryArgs {
    what: What,
    /// Scene file whose triangles are queried.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// OBJ files, in order (primitive ids run across them in this order).
    #[arg(long, num_args = 1..)]
    obj: Vec<PathBuf>,
    /// Point file: 3 little-endian f32 per point (x y z), no header.
    #[arg(long)]
    points: Option<PathBuf>,
    /// Ray file (count, list): 8 little-endian f32 per ray (ox oy oz tmin dx dy dz tmax).
    #[arg(long)]
    rays: Option<PathBuf>,
    /// Output file of records (docs/ray-query.md).
    #[arg(short, long)]
    output: PathBuf,
    #[arg(long, value_enum, default_value_t)]
    device: Device,
    /// closest: only triangles within this distance count (beyond it, the
    /// record's primitive is 0xFFFFFFFF) [default: no limit].
    #[arg(long, value_parser = non_negative)]
    max_distance: Option<f32>,
    /// signed-distance and inside: how inside is told [default: winding].
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    adapter: AdapterArgs,
}

impl QueryArgs {
    /// The query, and its input file, from the options (refusing those
    /// that do not apply to it).
    fn kind(&self) -> Result<(QueryKind, &Path)> {
        let what = self.what;
        let refuse = |option: &str| {
            Err(Error::Usage(format!(
                "{option} does not apply to `lambert query {}`",
                what.to_possible_value()
                    .expect("no skipped values")
                    .get_name()
            )))
        };
        if self.max_distance.is_some() && what != What::Closest {
            return refuse("--max-distance");
        }
        if self.method.is_some() && !matches!(what, What::SignedDistance | What::Inside) {
            return refuse("--method");
        }
        let sign = self.method.map(Sign::from).unwrap_or_default();
        let points = match what {
            What::Closest => PointQuery::Closest {
                max_distance: self.max_distance.unwrap_or(f32::INFINITY),
            },
            What::Distance => PointQuery::Distance,
            What::SignedDistance => PointQuery::SignedDistance(sign),
            What::Inside => PointQuery::Inside(sign),
            What::Count | What::List => {
                if self.points.is_some() {
                    return refuse("--points (it takes --rays)");
                }
                let rays = self.rays.as_deref().ok_or_else(|| {
                    Error::Usage("count and list take a ray file: give --rays RAYS.bin".into())
                })?;
                let query = if what == What::Count {
                    RayQuery::Count
                } else {
                    RayQuery::List
                };
                return Ok((QueryKind::Rays(query), rays));
            }
        };
        if self.rays.is_some() {
            return refuse("--rays (it takes --points)");
        }
        let input = self.points.as_deref().ok_or_else(|| {
            Error::Usage("this query takes a point file: give --points POINTS.bin".into())
        })?;
        Ok((QueryKind::Points(points), input))
    }
}

pub(super) fn query(args: &QueryArgs, quiet: bool) -> Result<ExitCode> {
    let (kind, input) = args.kind()?;
    let inputs: Vec<&Path> = [input]
        .into_iter()
        .chain(args.scene.as_deref())
        .chain(args.obj.iter().map(PathBuf::as_path))
        .collect();
    lambert::output::prepare_output_for(&args.output, &inputs)?;
    let scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::from_objs(&args.obj)?,
    };
    scene.check_output(&args.output)?;
    print_warnings(&scene, None, quiet);
    let job = QueryJob {
        kind,
        input,
        output: &args.output,
        device: args.device.into(),
        adapter: &args.adapter.request(),
    };
    let report = run_query(scene, &job, progress_bar::unless_quiet(quiet))?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).expect("report serialises")
        );
    }
    if !quiet {
        let found = match kind {
            QueryKind::Points(PointQuery::Closest { max_distance }) if max_distance.is_finite() => {
                format!("{} within {max_distance}", report.found)
            }
            QueryKind::Points(PointQuery::Closest { .. } | PointQuery::Distance) => String::new(),
            QueryKind::Points(_) => format!("{} inside", report.found),
            QueryKind::Rays(_) => format!("{} crossings", report.found),
        };
        eprintln!(
            "{} of {} {} on {}{}{}: {:.3} s; wrote {} records to {}; read {:.3} s, write {:.3} s",
            args.what
                .to_possible_value()
                .expect("no skipped values")
                .get_name(),
            report.queries,
            if matches!(kind, QueryKind::Rays(_)) {
                "rays"
            } else {
                "points"
            },
            report.device,
            if found.is_empty() { "" } else { ", " },
            found,
            report.query_seconds,
            report.records,
            args.output.display(),
            report.read_seconds,
            report.write_seconds
        );
    }
    Ok(ExitCode::SUCCESS)
}
