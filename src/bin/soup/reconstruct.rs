//! `soup reconstruct`: two photos in, depth, point clouds of both frames and a report out.

use std::path::PathBuf;

use superpixel_soup::camera::Intrinsics;
use superpixel_soup::export::{self, ExportFile};
use superpixel_soup::formats::ply::Encoding;
use superpixel_soup::formats::{flo, read_file, write_file};
use superpixel_soup::image::read_image_file;
use superpixel_soup::input::{DEFAULT_MAX_SIDE, prepare_pair};
use superpixel_soup::{Error, FlowInput, Result, reconstruct};

use crate::params::{PipelineArgs, all_defaults_help};

/// Reconstruct a dense 3D model of both frames from two photos.
#[derive(clap::Args)]
#[command(after_long_help = all_defaults_help())]
pub struct Args {
    /// Reference frame (PNG or JPEG).
    frame1: PathBuf,
    /// Second frame, same size as the first.
    frame2: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Intrinsics "fx fy cx cy" in pixels of the input images (default: EXIF, else a guess).
    #[arg(long)]
    intrinsics: Option<String>,
    /// Flow 1→2 as a Middlebury .flo file (any resolution; it is resampled). Without it the flow
    /// is computed (DIS with variational refinement, forward–backward checked).
    #[arg(long)]
    flow: Option<PathBuf>,
    #[command(flatten)]
    pipeline: PipelineArgs,
    /// Long side of the working resolution, in pixels.
    #[arg(long, default_value_t = DEFAULT_MAX_SIDE)]
    max_side: usize,
    /// Skip the refinement step (planes, motions and scales by particle belief propagation with
    /// TRW-S): faster, usually less accurate.
    #[arg(long)]
    no_refine: bool,
    /// Write PLY files as ASCII instead of binary.
    #[arg(long)]
    ascii: bool,
}

pub fn run(args: Args) -> Result<()> {
    let image1 = read_image_file(&args.frame1)?;
    let image2 = read_image_file(&args.frame2)?;
    let user = args
        .intrinsics
        .as_deref()
        .map(Intrinsics::parse)
        .transpose()?;
    let flow = match &args.flow {
        Some(path) => FlowInput::Given(flo::decode(&read_file(path)?)?),
        None => FlowInput::Compute(args.pipeline.flow_params()?),
    };
    let pair = prepare_pair(image1, image2, user, args.max_side)?;
    let mut params = args.pipeline.params()?;
    if args.no_refine {
        params.refine.iterations = 0;
    }
    let rec = reconstruct(&pair, flow, &params, &mut |stage, fraction| {
        if fraction == 0.0 {
            eprintln!("{}…", stage.name());
        }
    })?;
    std::fs::create_dir_all(&args.out).map_err(|e| Error::io(&args.out, e))?;
    let out = |name: &str| args.out.join(name);
    let encoding = if args.ascii {
        Encoding::Ascii
    } else {
        Encoding::BinaryLittleEndian
    };
    for file in ExportFile::ALL {
        write_file(
            &out(file.file_name()),
            &export::encode(&rec, file, encoding)?,
        )?;
    }
    let total: f64 = rec.report.timings_ms.iter().map(|t| t.1).sum();
    println!(
        "{} superpixels, {} motion hypotheses, {} degenerate; intrinsics from {}; {:.0} ms; wrote {}",
        rec.report.superpixels,
        rec.report.hypotheses,
        rec.report.degenerate,
        rec.report.camera.source,
        total,
        args.out.display()
    );
    Ok(())
}
