//! `soup synth`: render the synthetic scenes into case folders with exact ground truth.

use std::path::PathBuf;
use std::time::Instant;

use superpixel_soup::Grid;
use superpixel_soup::Result;
use superpixel_soup::colormap::depth_picture;
use superpixel_soup::formats::case::{Case, write_case};
use superpixel_soup::formats::write_file;
use superpixel_soup::image::{Frame, encode_png};
use superpixel_soup::synth::{SceneKind, render};

/// Render synthetic dynamic scenes with exact depth and flow, in the evaluation case layout.
#[derive(clap::Args)]
pub struct Args {
    /// Folder to write into; each scene goes to OUT_DIR/SCENE/ (its name, e.g. OUT_DIR/street/).
    out_dir: PathBuf,
    /// Scene to render (static-room, street, crowd, flag, creature, road, table) or `all`.
    #[arg(long, default_value = "all")]
    scene: String,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x436", value_parser = parse_size)]
    size: (usize, usize),
    /// Also write `preview.png` in each scene folder: frame 1, frame 2 and the depth picture
    /// stacked.
    #[arg(long)]
    preview: bool,
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
        let depth1 = scene.depth1;
        let dir = args.out_dir.join(kind.name());
        let case = Case {
            name: kind.name().to_string(),
            frame1: scene.frame1,
            frame2: scene.frame2,
            intrinsics: Some(scene.intrinsics),
            depth1: Some(depth1.clone()),
            flow12: Some(scene.flow12),
            depth12: Some(scene.depth12),
            moving1: Some(scene.moving1),
            groups1: Some(scene.group1),
        };
        write_case(&dir, &case)?;
        if args.preview {
            let preview = stack(&[&case.frame1, &case.frame2, &depth_picture(&depth1)]);
            write_file(&dir.join("preview.png"), &encode_png(&preview)?)?;
        }
        println!(
            "{:<12} {width}×{height} → {} ({:.2} s)",
            kind.name(),
            dir.display(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Frames of one width stacked top to bottom.
fn stack(frames: &[&Frame]) -> Frame {
    let width = frames[0].width();
    let rows: Vec<[u8; 3]> = frames
        .iter()
        .flat_map(|f| f.data().iter().copied())
        .collect();
    let height = rows.len() / width;
    Grid::from_fn(width, height, |x, y| rows[y * width + x])
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
