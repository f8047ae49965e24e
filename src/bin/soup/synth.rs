//! `soup synth`: render the synthetic scenes into case folders with exact ground truth.

use std::path::PathBuf;
use std::time::Instant;

use superpixel_soup::Result;
use superpixel_soup::formats::case::{Case, write_case};
use superpixel_soup::synth::{SceneKind, render};

/// Render synthetic dynamic scenes with exact depth and flow, in the evaluation case layout.
#[derive(clap::Args)]
pub struct Args {
    /// Folder to write into; each scene goes to OUT_DIR/<scene name>/.
    out_dir: PathBuf,
    /// Scene to render (static-room, street, crowd, flag) or `all`.
    #[arg(long, default_value = "all")]
    scene: String,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x436", value_parser = parse_size)]
    size: (usize, usize),
}

pub fn run(args: Args) -> Result<()> {
    let scenes = if args.scene == "all" {
        SceneKind::ALL.to_vec()
    } else {
        vec![SceneKind::from_name(&args.scene)?]
    };
    let (width, height) = args.size;
    for kind in scenes {
        let start = Instant::now();
        let scene = render(kind, width, height)?;
        let dir = args.out_dir.join(kind.name());
        let case = Case {
            name: kind.name().to_string(),
            frame1: scene.frame1,
            frame2: scene.frame2,
            intrinsics: Some(scene.intrinsics),
            depth1: Some(scene.depth1),
            flow12: Some(scene.flow12),
            moving1: Some(scene.moving1),
            groups1: Some(scene.group1),
        };
        write_case(&dir, &case)?;
        println!(
            "{:<12} {width}×{height} → {} ({:.2} s)",
            kind.name(),
            dir.display(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Parses `WIDTHxHEIGHT` (also `×` or `X`).
fn parse_size(text: &str) -> std::result::Result<(usize, usize), String> {
    let parts: Vec<&str> = text.split(['x', 'X', '×']).collect();
    match parts.as_slice() {
        [w, h] => match (w.trim().parse(), h.trim().parse()) {
            (Ok(w), Ok(h)) => Ok((w, h)),
            _ => Err(format!("size must be WIDTHxHEIGHT, got {text:?}")),
        },
        _ => Err(format!("size must be WIDTHxHEIGHT, got {text:?}")),
    }
}
