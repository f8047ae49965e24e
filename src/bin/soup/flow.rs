//! `soup flow`: dense optical flow between two frames, or its accuracy on evaluation cases.

use std::path::PathBuf;
use std::time::Instant;

use superpixel_soup::eval::flow_metrics;
use superpixel_soup::flow::colour::flow_picture_with_reliability;
use superpixel_soup::flow::{FlowField, FlowParams, Preset, compute_flow};
use superpixel_soup::formats::case::read_case;
use superpixel_soup::formats::{flo, write_file};
use superpixel_soup::image::{encode_png, read_image_file};
use superpixel_soup::{Error, Grid, Result};

/// Compute dense optical flow (DIS with variational refinement) both ways between two frames,
/// or score it against the flow12.flo of evaluation cases (`--eval`).
#[derive(clap::Args)]
pub struct Args {
    /// Frame 1 and frame 2 (PNG or JPEG, same size).
    #[arg(num_args = 0..=2, value_name = "FRAME")]
    frames: Vec<PathBuf>,
    /// Write the flow frame 1 → frame 2 here (Middlebury .flo).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write the flow frame 2 → frame 1 here (.flo).
    #[arg(long)]
    backward: Option<PathBuf>,
    /// Also write a Middlebury colour picture of the forward flow here (PNG); vectors failing the
    /// forward–backward check are drawn darker.
    #[arg(long)]
    viz: Option<PathBuf>,
    /// Speed/accuracy preset: fast, medium, fine or high.
    #[arg(long, default_value_t = Preset::default().name().to_string())]
    preset: String,
    /// Instead of two frames, score the flow on these case folders (frame1.png, frame2.png,
    /// flow12.flo) and print a table.
    #[arg(long, num_args = 1.., value_name = "CASE_DIR", conflicts_with_all = ["frames", "out", "backward", "viz"])]
    eval: Vec<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let params = FlowParams::preset(Preset::from_name(&args.preset)?);
    if !args.eval.is_empty() {
        return evaluate(&args.eval, &params, &args.preset);
    }
    let [frame1, frame2] = args.frames.as_slice() else {
        return Err(Error::InvalidParameter(
            "give two frames (soup flow FRAME1 FRAME2 --out flow.flo) or --eval CASE_DIR...".into(),
        ));
    };
    let Some(out) = &args.out else {
        return Err(Error::InvalidParameter(
            "--out FLOW.flo is required with two frames".into(),
        ));
    };
    let image1 = read_image_file(frame1)?;
    let image2 = read_image_file(frame2)?;
    let start = Instant::now();
    let pair = compute_flow(&image1.frame, &image2.frame, &params, &mut |_| {})?;
    let seconds = start.elapsed().as_secs_f64();
    write_file(out, &flo::encode(&pair.forward))?;
    if let Some(path) = &args.backward {
        write_file(path, &flo::encode(&pair.backward))?;
    }
    if let Some(path) = &args.viz {
        let picture = flow_picture_with_reliability(&pair.forward, &pair.reliable);
        write_file(path, &encode_png(&picture)?)?;
    }
    let (w, h) = pair.forward.size();
    println!(
        "{w}×{h}, preset {}: {:.1} % of vectors pass the forward–backward check; {:.3} s; wrote {}",
        args.preset,
        100.0 * share(pair.reliable.data()),
        seconds,
        out.display()
    );
    Ok(())
}

/// Prints the EPE table of the cases in `dirs`.
fn evaluate(dirs: &[PathBuf], params: &FlowParams, preset: &str) -> Result<()> {
    println!("Flow, preset {preset} (forward + backward timed together)\n");
    println!("| case | size | EPE | share EPE > 3 px | reliable | EPE on reliable | seconds |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    let mut epes = Vec::new();
    for dir in dirs {
        let case = read_case(dir)?;
        let gt = case.flow12.as_ref().ok_or_else(|| {
            Error::InvalidParameter(format!("case {} has no flow12.flo to score", case.name))
        })?;
        let start = Instant::now();
        let pair = compute_flow(&case.frame1, &case.frame2, params, &mut |_| {})?;
        let seconds = start.elapsed().as_secs_f64();
        let all = flow_metrics(gt, &pair.forward)?;
        let (w, h) = case.frame1.size();
        let masked: FlowField = Grid::from_fn(w, h, |x, y| {
            if *pair.reliable.get(x, y) {
                *pair.forward.get(x, y)
            } else {
                [f32::NAN; 2]
            }
        });
        let reliable_epe =
            flow_metrics(gt, &masked).map_or("–".to_string(), |m| format!("{:.3}", m.epe));
        println!(
            "| {} | {w}×{h} | {:.3} | {:.3} | {:.3} | {reliable_epe} | {seconds:.3} |",
            case.name,
            all.epe,
            all.over_3px,
            share(pair.reliable.data()),
        );
        epes.push(all.epe);
    }
    if epes.len() > 1 {
        println!(
            "| mean | | {:.3} | | | | |",
            epes.iter().sum::<f64>() / epes.len() as f64
        );
    }
    Ok(())
}

/// Share of `true` in a mask.
fn share(mask: &[bool]) -> f64 {
    mask.iter().filter(|&&m| m).count() as f64 / mask.len().max(1) as f64
}
