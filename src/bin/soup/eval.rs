//! `soup eval`: run the pipeline on evaluation cases and print accuracy per case.

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;
use superpixel_soup::camera::resolve_intrinsics;
use superpixel_soup::eval::{DepthMetrics, depth_metrics, median};
use superpixel_soup::flow::{FlowParams, Preset};
use superpixel_soup::formats::case::{Case, read_case};
use superpixel_soup::formats::write_file;
use superpixel_soup::grid::Grid;
use superpixel_soup::image::{ExifInfo, LoadedImage};
use superpixel_soup::input::{DEFAULT_MAX_SIDE, prepare_pair};
use superpixel_soup::output::depth_at;
use superpixel_soup::soup::arap::{ScaleInputs, scale_energy};
use superpixel_soup::{Error, FlowInput, Params, Reconstruction, Result, reconstruct};

/// Run the reconstruction on cases in the evaluation layout and score the depth.
#[derive(clap::Args)]
pub struct Args {
    /// Case folders (frame1.png, frame2.png, intrinsics.txt, depth1.pfm or depth1.dpt, flow12.flo).
    #[arg(required = true)]
    cases: Vec<PathBuf>,
    /// Use the case's ground-truth flow12.flo instead of computed flow (the oracle-flow ablation).
    #[arg(long)]
    gt_flow: bool,
    /// Preset of the computed flow: fast, medium or high.
    #[arg(long, default_value = "medium")]
    preset: String,
    /// Also write all numbers as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Requested number of superpixels.
    #[arg(long, default_value_t = 1500)]
    superpixels: usize,
    /// Neighbours in the K-NN graph.
    #[arg(long, default_value_t = 15)]
    k: usize,
    /// Also print, per motion hypothesis in use, its superpixels, the ground-truth motion group
    /// most of its pixels belong to (and that share) and the error of its solved scale.
    #[arg(long)]
    groups: bool,
}

/// Numbers for one case.
#[derive(Serialize)]
struct CaseResult {
    case: String,
    metrics: DepthMetrics,
    /// MRE with each superpixel of the unit-scale soup given its oracle scale (motion/plane error).
    oracle_superpixel_mre: f64,
    /// MRE with one oracle scale per ground-truth motion group (when the case has groups1.png).
    oracle_group_mre: Option<f64>,
    seconds: f64,
    hypotheses: usize,
    degenerate: usize,
    energy_start: f64,
    energy_end: f64,
}

pub fn run(args: Args) -> Result<()> {
    let mut params = Params::default();
    params.superpixels.count = args.superpixels;
    params.k = args.k;
    let flow_params = FlowParams::preset(Preset::from_name(&args.preset)?);
    println!(
        "| case | MRE | AbsRel | δ<1.25 | coverage | oracle-superpixel MRE | oracle-group MRE | hypotheses | seconds |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut results = Vec::new();
    for dir in &args.cases {
        let case = read_case(dir)?;
        let computed = (!args.gt_flow).then_some(flow_params);
        let (result, rec) = evaluate(&case, &params, computed)?;
        println!(
            "| {} | {:.4} | {:.4} | {:.3} | {:.3} | {:.4} | {} | {} | {:.2} |",
            result.case,
            result.metrics.mre,
            result.metrics.abs_rel,
            result.metrics.delta_125,
            result.metrics.coverage,
            result.oracle_superpixel_mre,
            result
                .oracle_group_mre
                .map_or("–".into(), |m| format!("{m:.4}")),
            result.hypotheses,
            result.seconds
        );
        results.push(result);
        if args.groups {
            print_groups(&rec, &case);
        }
    }
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&results)
            .map_err(|e| Error::InvalidParameter(e.to_string()))?;
        write_file(path, text.as_bytes())?;
    }
    Ok(())
}

/// Reconstructs `case` with flow computed with `computed` parameters, or with its ground-truth
/// flow when `None`, and scores the depth.
fn evaluate(
    case: &Case,
    params: &Params,
    computed: Option<FlowParams>,
) -> Result<(CaseResult, Reconstruction)> {
    let gt = case.depth1.as_ref().ok_or_else(|| {
        Error::InvalidParameter(format!(
            "case {} has no depth1.pfm or depth1.dpt to score against",
            case.name
        ))
    })?;
    let flow = match computed {
        Some(flow_params) => FlowInput::Compute(flow_params),
        None => FlowInput::Given(case.flow12.clone().ok_or_else(|| {
            Error::InvalidParameter(format!(
                "case {} has no flow12.flo for --gt-flow",
                case.name
            ))
        })?),
    };
    let (w, h) = case.frame1.size();
    let camera = resolve_intrinsics(case.intrinsics, None, w, h);
    let loaded = |frame: &Grid<[u8; 3]>| LoadedImage {
        frame: frame.clone(),
        exif: ExifInfo::default(),
    };
    let pair = prepare_pair(
        loaded(&case.frame1),
        loaded(&case.frame2),
        Some(camera.intrinsics),
        DEFAULT_MAX_SIDE,
    )?;
    let start = Instant::now();
    let rec = reconstruct(&pair, flow, params, &mut |_, _| {})?;
    let seconds = start.elapsed().as_secs_f64();
    let metrics = depth_metrics(gt, &rec.depth_input)?;
    let (oracle_superpixel_mre, oracle_group_mre) = oracles(&rec, case, gt, &camera.intrinsics);
    let result = CaseResult {
        case: case.name.clone(),
        metrics,
        oracle_superpixel_mre,
        oracle_group_mre,
        seconds,
        hypotheses: rec.report.hypotheses,
        degenerate: rec.report.degenerate,
        energy_start: rec.report.arap.energy_start,
        energy_end: rec.report.arap.energy_end,
    };
    Ok((result, rec))
}

/// Per motion hypothesis in use: superpixels, pixels, the ground-truth group holding most of its
/// pixels and that share (purity), and its scale error: the solved λ (after the global median
/// alignment) over the oracle scale median(z_gt / z) of its own pixels, minus 1; and the part of
/// the MRE its pixels make up.
fn print_groups(rec: &Reconstruction, case: &Case) {
    let Some(gt) = case.depth1.as_ref() else {
        return;
    };
    let labels = &rec.superpixels.labels;
    if gt.size() != labels.size() {
        println!("(--groups needs the case at the working resolution)");
        return;
    }
    let hyps = rec.soup.hypotheses.len();
    let mut ratios = vec![Vec::new(); hyps];
    let mut pieces = vec![0usize; hyps];
    let mut gt_groups = vec![[0usize; 256]; hyps];
    for p in &rec.soup.pieces {
        pieces[p.hypothesis] += 1;
    }
    let mut all = Vec::new();
    for (i, (&l, &g)) in labels.data().iter().zip(gt.data()).enumerate() {
        let z = rec.depth.data()[i];
        let h = rec.soup.pieces[l as usize].hypothesis;
        if let Some(groups) = &case.groups1 {
            gt_groups[h][groups.data()[i] as usize] += 1;
        }
        if g.is_finite() && g > 0.0 && z.is_finite() && z > 0.0 {
            ratios[h].push(g as f64 / z as f64);
            all.push(g as f64 / z as f64);
        }
    }
    if all.is_empty() {
        return;
    }
    let valid = all.len() as f64;
    let global = median(all);
    // The energy of the scale solve at its solution and at oracle scales (one per hypothesis):
    // oracle lower than solved means the solver missed; higher means the energy is wrong there.
    let mut oracle_soup = rec.unit_soup.clone();
    let mut unit_ratios = vec![Vec::new(); hyps];
    for (i, (&l, &g)) in labels.data().iter().zip(gt.data()).enumerate() {
        let piece = &rec.unit_soup.pieces[l as usize];
        let (x, y) = ((i % labels.width()) as f64, (i / labels.width()) as f64);
        let z = piece.depth(&nalgebra::Vector3::from(
            rec.report.camera.intrinsics.ray(x, y),
        ));
        if g.is_finite() && g > 0.0 && z.is_finite() && z > 0.0 {
            unit_ratios[piece.hypothesis].push(g as f64 / z);
        }
    }
    let oracle: Vec<f64> = unit_ratios
        .into_iter()
        .map(|r| if r.is_empty() { f64::NAN } else { median(r) })
        .collect();
    for p in &mut oracle_soup.pieces {
        p.lambda = if oracle[p.hypothesis].is_finite() {
            oracle[p.hypothesis]
        } else {
            1.0
        };
    }
    let inputs = ScaleInputs {
        superpixels: &rec.superpixels,
        knn: &rec.knn,
        boundaries: &rec.boundaries,
        flow: &rec.flow,
        intrinsics: &rec.report.camera.intrinsics,
    };
    let energy =
        |soup: &superpixel_soup::soup::Soup| scale_energy(soup, &inputs, &rec.report.params.scales);
    println!(
        "scale energy: solved {:.3}, oracle scales {:.3}",
        energy(&rec.soup),
        energy(&oracle_soup)
    );
    println!(
        "| hypothesis | superpixels | pixels | main GT group | purity | scale error | MRE share |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for h in 0..hyps {
        if pieces[h] == 0 || ratios[h].is_empty() {
            continue;
        }
        let count = ratios[h].len();
        let (main, share) = gt_groups[h]
            .iter()
            .enumerate()
            .max_by_key(|&(g, &c)| (c, std::cmp::Reverse(g)))
            .map(|(g, &c)| {
                (
                    g,
                    c as f64 / gt_groups[h].iter().sum::<usize>().max(1) as f64,
                )
            })
            .unwrap_or((0, 0.0));
        // This hypothesis's pixels' part of the MRE (the column sums to the MRE).
        let mre_share = ratios[h]
            .iter()
            .map(|r| (global / r - 1.0).abs())
            .sum::<f64>()
            / valid;
        let oracle = median(ratios[h].clone());
        println!(
            "| {h} | {} | {count} | {} | {:.2} | {:+.3} | {mre_share:.4} |",
            pieces[h],
            if case.groups1.is_some() {
                main.to_string()
            } else {
                "–".into()
            },
            share,
            global / oracle - 1.0,
        );
    }
}

/// MRE of the unit-scale soup with oracle scales: per superpixel (median z_gt / z over its
/// pixels), and per ground-truth motion group when the case has one.
fn oracles(
    rec: &Reconstruction,
    case: &Case,
    gt: &Grid<f32>,
    k: &superpixel_soup::camera::Intrinsics,
) -> (f64, Option<f64>) {
    let (w, h) = gt.size();
    let unit = depth_at(&rec.unit_soup, &rec.superpixels.labels, w, h, k);
    let labels = &rec.superpixels.labels;
    let (lw, lh) = labels.size();
    let label_at = |x: usize, y: usize| {
        let lx = ((x as f64 + 0.5) * lw as f64 / w as f64 - 0.5)
            .round()
            .clamp(0.0, (lw - 1) as f64) as usize;
        let ly = ((y as f64 + 0.5) * lh as f64 / h as f64 - 0.5)
            .round()
            .clamp(0.0, (lh - 1) as f64) as usize;
        *labels.get(lx, ly) as usize
    };
    let scaled_by = |key: &dyn Fn(usize, usize) -> usize, keys: usize| -> f64 {
        let mut ratios = vec![Vec::new(); keys];
        for y in 0..h {
            for x in 0..w {
                let (g, z) = (*gt.get(x, y), *unit.get(x, y));
                if g.is_finite() && g > 0.0 && z.is_finite() && z > 0.0 {
                    ratios[key(x, y)].push(g as f64 / z as f64);
                }
            }
        }
        let scales: Vec<f64> = ratios
            .into_iter()
            .map(|r| if r.is_empty() { f64::NAN } else { median(r) })
            .collect();
        let est = Grid::from_fn(w, h, |x, y| {
            (*unit.get(x, y) as f64 * scales[key(x, y)]) as f32
        });
        depth_metrics(gt, &est).map_or(f64::NAN, |m| m.mre)
    };
    let per_superpixel = scaled_by(&label_at, rec.superpixels.len());
    let per_group = case
        .groups1
        .as_ref()
        .map(|g| scaled_by(&|x, y| *g.get(x, y) as usize, 256));
    (per_superpixel, per_group)
}
