//! `lambert view`'s arguments, handed to the viewer (src/bin/lambert/view/).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use lambert::camera::navigate::INTERACTIVE_SPP;
use lambert::error::{Error, Result};
use lambert::limits::validate_spp;

use super::load_for;
use super::options::SceneArgs;

use crate::view::{Settings, view};

#[derive(Args)]
#[command(mut_arg("spp", |a| a.help(
    "Samples per pixel the image is refined to, one a frame [default: the scene's render.spp, else 1024]"
)))]
pub(super) struct ViewArgs {
    #[command(flatten)]
    input: SceneArgs,
    /// Render N frames of one sample per pixel each (the image `render
    /// --spp N` makes, bit for bit), write --screenshot and exit. Without
    /// it the image is refined up to --spp (default: the scene's
    /// render.spp, else 1024) and the window stays.
    #[arg(
        long,
        value_name = "N",
        conflicts_with = "spp",
        requires = "screenshot"
    )]
    frames: Option<u32>,
    /// Where --frames, and Shift+S, write the image (.png, .exr or .pfm)
    /// [default for Shift+S: lambert-view-NNN.png, the first free].
    #[arg(long, value_name = "PATH")]
    screenshot: Option<PathBuf>,
}

pub(super) fn run(args: ViewArgs, quiet: bool) -> Result<ExitCode> {
    if let Some(frames) = args.frames {
        validate_spp(frames).map_err(|e| Error::Usage(format!("--frames: {e}")))?;
    }
    let screenshot: Vec<&Path> = args.screenshot.as_deref().into_iter().collect();
    let (scene, settings) = load_for(&args.input, &screenshot, quiet)?;
    let spp = args
        .frames
        .or(args.input.options.spp())
        .or(scene.spp_given().then_some(scene.view().spp))
        .unwrap_or(INTERACTIVE_SPP);
    view(Settings {
        path: args.input.scene,
        // The viewer renders the scene as the options set it.
        scene: scene.with_settings(&settings),
        device: args.input.device.into(),
        request: args.input.adapter.request(),
        spp,
        frames: args.frames.is_some(),
        screenshot: args.screenshot,
        quiet,
    })
}
