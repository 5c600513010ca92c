//! `pathtracer view`: the interactive viewer.

use anyhow::Result;
use pt_render::output;

use super::load_scene;
use crate::{ViewArgs, viewer};

/// Opens the viewer.
pub(crate) fn run(args: &ViewArgs) -> Result<()> {
    if let Some(shot) = &args.screenshot {
        output::check_writable(shot)?;
    }
    let scene = load_scene(args.scene.as_ref())?;
    viewer::run(viewer::ViewArgs {
        scene,
        scene_path: args.scene.clone(),
        width: args.width,
        height: args.height,
        target_spp: args.spp,
        max_bounces: args.max_bounces,
        frames: args.frames,
        screenshot: args.screenshot.clone(),
    })
}
