//! `soup eval`: run the pipeline on evaluation cases and print accuracy per case.

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;
use superpixel_soup::camera::Intrinsics;
use superpixel_soup::camera::resolve_intrinsics;
use superpixel_soup::eval::{
    DepthMetrics, MotionError, depth_metrics, median, motion_error, true_camera_motion, true_states,
};
use superpixel_soup::flow::FlowParams;
use superpixel_soup::formats::case::{Case, read_case};
use superpixel_soup::formats::write_file;
use superpixel_soup::grid::Grid;
use superpixel_soup::input::{DEFAULT_MAX_SIDE, prepare_pair};
use superpixel_soup::output::{depth_at, nearest_label};
use superpixel_soup::soup::scales;
use superpixel_soup::soup::{Soup, refine};
use superpixel_soup::{Error, FlowInput, Params, Reconstruction, Result, reconstruct};

use crate::params::{PipelineArgs, all_defaults_help};
use superpixel_soup::numeric::{exp, ln};

/// Run the reconstruction on cases in the evaluation layout and score the depth.
#[derive(clap::Args)]
#[command(after_long_help = all_defaults_help())]
pub struct Args {
    /// Case folders (frame1.png, frame2.png, intrinsics.txt, depth1.pfm or depth1.dpt, flow12.flo).
    #[arg(required = true)]
    cases: Vec<PathBuf>,
    /// Use the case's ground-truth flow12.flo instead of computed flow (the oracle-flow ablation).
    #[arg(long)]
    gt_flow: bool,
    /// Also write all numbers as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    pipeline: PipelineArgs,
    /// Also print, per motion hypothesis in use, its superpixels, the ground-truth motion group
    /// most of its pixels belong to (and that share) and the error of its solved scale; and, for
    /// a case with groups1.png, per ground-truth group its MRE, depth ratio and share of the MRE.
    #[arg(long)]
    groups: bool,
    /// Also run the truth test: the scale energy and MRE of the solution, of the oracle scales
    /// (each superpixel at median(z_gt / z) of its pixels) and of both polished by the solver's
    /// per-piece descent; the refinement's energy by term at the solution, the
    /// oracle scales and, where the case has scene flow (depth12.pfm), every piece at its true
    /// motion and plane, each also refined.
    #[arg(long)]
    oracle: bool,
}

/// Numbers for one case.
#[derive(Serialize)]
struct CaseResult {
    case: String,
    metrics: DepthMetrics,
    /// The metrics over pixels whose superpixel's scale is confident (its coverage is their
    /// share of the valid pixels).
    confident: DepthMetrics,
    /// MRE with each superpixel of the unit-scale soup given its oracle scale (motion/plane error).
    oracle_superpixel_mre: f64,
    /// MRE with one oracle scale per ground-truth motion group (when the case has groups1.png).
    oracle_group_mre: Option<f64>,
    /// MRE of one constant depth everywhere (the floor a reconstruction must beat).
    constant_mre: f64,
    /// The error of the estimated ego-motion (motion hypothesis 0) against the camera's true
    /// motion (when the case has scene flow and a mask of what moves: the synthetic scenes).
    ego_error: Option<MotionError>,
    seconds: f64,
    hypotheses: usize,
    degenerate: usize,
    energy_start: f64,
    energy_end: f64,
}

pub fn run(args: Args) -> Result<()> {
    let params = args.pipeline.params()?;
    let flow_params = args.pipeline.flow_params()?;
    println!(
        "| case | MRE | AbsRel | δ<1.25 | coverage | MRE confident | confident share | oracle-superpixel MRE | oracle-group MRE | constant-depth MRE | ego-motion error t° / R° | hypotheses | seconds |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut results = Vec::new();
    for dir in &args.cases {
        let case = read_case(dir)?;
        let computed = (!args.gt_flow).then_some(flow_params);
        let (result, rec) = evaluate(&case, &params, computed)?;
        println!(
            "| {} | {:.4} | {:.4} | {:.3} | {:.3} | {:.4} | {:.3} | {:.4} | {} | {:.4} | {} | {} | {:.2} |",
            result.case,
            result.metrics.mre,
            result.metrics.abs_rel,
            result.metrics.delta_125,
            result.metrics.coverage,
            result.confident.mre,
            result.confident.coverage,
            result.oracle_superpixel_mre,
            result
                .oracle_group_mre
                .map_or("–".into(), |m| format!("{m:.4}")),
            result.constant_mre,
            result.ego_error.map_or("–".into(), |e| format!(
                "{:.2} / {:.3}",
                e.translation_deg, e.rotation_deg
            )),
            result.hypotheses,
            result.seconds
        );
        results.push(result);
        if args.groups {
            print_groups(&rec, &case);
        }
        if args.oracle {
            print_truth_test(&rec, &case)?;
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
    let pair = prepare_pair(
        case.frame1.clone().into(),
        case.frame2.clone().into(),
        Some(camera.intrinsics),
        DEFAULT_MAX_SIDE,
    )?;
    let start = Instant::now();
    let rec = reconstruct(&pair, flow, params, &mut |_, _| {})?;
    let seconds = start.elapsed().as_secs_f64();
    let metrics = depth_metrics(gt, &rec.depth_input)?;
    let confident = depth_metrics(gt, &confident_depth(&rec, gt.width(), gt.height()))?;
    let (oracle_superpixel_mre, oracle_group_mre) = oracles(&rec, case, gt, &camera.intrinsics);
    let result = CaseResult {
        case: case.name.clone(),
        metrics,
        confident,
        oracle_superpixel_mre,
        oracle_group_mre,
        constant_mre: depth_metrics(gt, &Grid::filled(gt.width(), gt.height(), 1.0f32))?.mre,
        ego_error: ego_error(&rec, case, gt, &camera.intrinsics)?,
        seconds,
        hypotheses: rec.report.hypotheses,
        degenerate: rec.report.degenerate,
        energy_start: rec.report.scales.energy_start,
        energy_end: rec.report.scales.energy_end,
    };
    Ok((result, rec))
}

/// The error of `rec`'s ego-motion (its unit-scale soup's hypothesis 0) against the camera's
/// true motion, when `case` has scene flow and `moving1.png` (`k`: the case's intrinsics at its
/// own resolution, where its truths are).
fn ego_error(
    rec: &Reconstruction,
    case: &Case,
    depth1: &Grid<f32>,
    k: &Intrinsics,
) -> Result<Option<MotionError>> {
    let (Some(moving), Some(flow12), Some(depth12), Some(ego)) = (
        &case.moving1,
        &case.flow12,
        &case.depth12,
        rec.unit_soup.hypotheses.first(),
    ) else {
        return Ok(None);
    };
    let truth = true_camera_motion(moving, depth1, flow12, depth12, k)?;
    Ok(truth.map(|truth| motion_error(ego, &truth)))
}

/// The depth at the input resolution (`width` × `height`) where the superpixel's scale is
/// confident, NaN elsewhere.
fn confident_depth(rec: &Reconstruction, width: usize, height: usize) -> Grid<f32> {
    let labels = &rec.superpixels.labels;
    let min = rec.report.params.scales.min_confidence;
    Grid::from_fn(width, height, |x, y| {
        if rec.report.confidence[nearest_label(labels, width, height, x, y)] >= min {
            *rec.depth_input.get(x, y)
        } else {
            f32::NAN
        }
    })
}

/// Per motion hypothesis in use: superpixels, pixels, the ground-truth group holding most of its
/// pixels and that share (purity), and its scale error: the solved λ (after the global median
/// alignment) over the oracle scale median(z_gt / z) of its own pixels, minus 1; and the part of
/// the MRE its pixels make up. Then, for a case with `groups1.png`, the same seen from each
/// ground-truth group ([`print_truth_groups`]).
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
    // (pixel, hypothesis, z_gt / z) of every pixel valid in both maps.
    let mut valid_pixels = Vec::new();
    for (i, (&l, &g)) in labels.data().iter().zip(gt.data()).enumerate() {
        let z = rec.depth.data()[i];
        let h = rec.soup.pieces[l as usize].hypothesis;
        if let Some(groups) = &case.groups1 {
            gt_groups[h][groups.data()[i] as usize] += 1;
        }
        if g.is_finite() && g > 0.0 && z.is_finite() && z > 0.0 {
            ratios[h].push(g as f64 / z as f64);
            valid_pixels.push((i, h, g as f64 / z as f64));
        }
    }
    if valid_pixels.is_empty() {
        return;
    }
    let valid = valid_pixels.len() as f64;
    let global = median(valid_pixels.iter().map(|p| p.2).collect());
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
    if let Some(groups) = &case.groups1 {
        print_truth_groups(&valid_pixels, global, groups, hyps);
    }
}

/// Per ground-truth motion group (`groups`: 0 the static world, 1.. each mover): its valid
/// pixels, its MRE, its depth ratio (the median over its pixels of s·z / z_gt after the global
/// median alignment s = `global`: below 1 too near, above 1 too far), its part of the MRE (the
/// column sums to the MRE), and the motion hypothesis most of its pixels are on, with that
/// share. Where a reconstruction's error sits, object by object. `valid_pixels` holds
/// (pixel, hypothesis, z_gt / z) of every pixel valid in both depth maps; `hyps` is the number
/// of hypotheses.
fn print_truth_groups(
    valid_pixels: &[(usize, usize, f64)],
    global: f64,
    groups: &Grid<u8>,
    hyps: usize,
) {
    // (hypothesis, z_gt / z) of each group's valid pixels.
    let mut by_group = vec![Vec::new(); u8::MAX as usize + 1];
    for &(i, h, r) in valid_pixels {
        by_group[groups.data()[i] as usize].push((h, r));
    }
    let valid = valid_pixels.len() as f64;
    println!();
    println!("| GT group | pixels | MRE | depth ratio | MRE share | main hypothesis (share) |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for (group, mine) in by_group.iter().enumerate().filter(|(_, m)| !m.is_empty()) {
        let count = mine.len();
        let error: f64 = mine.iter().map(|p| (global / p.1 - 1.0).abs()).sum();
        let ratio = median(mine.iter().map(|p| global / p.1).collect());
        let mut on = vec![0usize; hyps];
        mine.iter().for_each(|p| on[p.0] += 1);
        let (main, most) = (0..hyps)
            .map(|h| (h, on[h]))
            .max_by_key(|&(h, c)| (c, std::cmp::Reverse(h)))
            .unwrap_or((0, 0));
        println!(
            "| {group} | {count} | {:.4} | {ratio:.3} | {:.4} | {main} ({:.2}) |",
            error / count as f64,
            error / valid,
            most as f64 / count as f64,
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
    let label_at = |x: usize, y: usize| nearest_label(labels, w, h, x, y);
    let scaled_by = |key: &dyn Fn(usize, usize) -> usize, keys: usize| -> f64 {
        let scales = oracle_ratios(&unit, gt, key, keys);
        let est = Grid::from_fn(w, h, |x, y| {
            (*unit.get(x, y) as f64 * scales[key(x, y)].unwrap_or(f64::NAN)) as f32
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

/// The truth test: the scale energy ([`scales::Problem`]) and the refinement energy
/// ([`refine::Problem`]) with the MRE, at the solution and at the ground truth (each superpixel at
/// its oracle scale median(z_gt / z̄) over its pixels), the truth then polished by the same
/// optimisers; for the refinement each energy's terms, and with the case's scene flow
/// (`depth12`) also every piece at its true rigid motion and plane ([`true_states`]), before and
/// after the same refinement. Truth that polishes to a higher energy than the solution's means
/// the energy prefers a wrong answer; lower means the optimiser missed it. For the scale energy
/// the solution is also polished by the same descent, since polishing never raises a state's
/// energy and lowers it wherever a piece can move: the two polished rows compare the basins
/// fairly. Also lists the pieces
/// that carry most of the solution's error.
fn print_truth_test(rec: &Reconstruction, case: &Case) -> Result<()> {
    let Some(gt) = case.depth1.as_ref() else {
        return Ok(());
    };
    let k_in = resolve_intrinsics(case.intrinsics, None, gt.width(), gt.height()).intrinsics;
    let labels = &rec.superpixels.labels;
    let (w, h) = gt.size();
    let oracle_ratios = piece_log_ratios(rec, &rec.unit_soup, gt, &k_in);
    let solved: Vec<f64> = rec.soup.pieces.iter().map(|p| ln(p.lambda)).collect();
    let oracle: Vec<f64> = oracle_ratios
        .iter()
        .zip(&solved)
        .map(|(r, &s)| r.unwrap_or(s))
        .collect();
    let inputs = rec.scale_inputs();
    let params = &rec.report.params;
    let mre_of = |soup: &Soup| -> Result<f64> {
        Ok(depth_metrics(gt, &depth_at(soup, labels, w, h, &k_in))?.mre)
    };
    let at = |s: &[f64]| {
        let mut soup = rec.unit_soup.clone();
        scales::set_scales(&mut soup, s);
        soup
    };
    println!("truth test of {}:", case.name);
    println!(
        "| energy | state | E | segment solve: contacts, static and rest priors + figure prior + ground prior | MRE |"
    );
    println!("| --- | --- | --- | --- | --- |");
    // The scale energy over per-piece log-scales of the unit-scale soup's planes and motions.
    let problem = scales::build_problem(&rec.unit_soup, &inputs, &params.scales);
    let scaled = &rec.scaled_soup;
    let solution: Vec<f64> = scaled.pieces.iter().map(|p| ln(p.lambda)).collect();
    let mut polished = oracle.clone();
    scales::polish(&problem, &mut polished, 50);
    // The same descent from the solution: polishing never raises a state's energy and lowers it
    // wherever a piece can move, so only the two polished states compare fairly (which basin
    // does the energy prefer?).
    let mut solution_polished = solution.clone();
    scales::polish(&problem, &mut solution_polished, 50);
    let as_segments = |descend| {
        scales::segment_descent_from(&rec.unit_soup, &inputs, &params.scales, &oracle, descend)
    };
    let (segments, segments_solved) = (as_segments(false), as_segments(true));
    for (name, s) in [
        ("scale solve", &solution),
        ("scale solve polished", &solution_polished),
        ("truth", &oracle),
        ("truth polished", &polished),
        ("truth as segments", &segments),
        ("truth as segments, solved", &segments_solved),
    ] {
        let segments = scales::segment_objective(&rec.unit_soup, &inputs, &params.scales, s);
        println!(
            "| scales | {name} | {:.3} | {:.3} + {:.3} + {:.3} | {:.4} |",
            problem.energy(s),
            segments.contacts,
            segments.figure,
            segments.ground,
            mre_of(&at(s))?
        );
    }
    // The refinement energy over full states: the "truth" keeps the soup's motions and planes
    // at the oracle scales; the true states (where the case has the scene flow) are each
    // piece's own rigid motion and plane from the ground truth.
    if params.refine.iterations > 0 {
        let refine_problem = refine::Problem::new(scaled, &inputs, &params.scales, &params.refine);
        // The refinement's own output (before the fusion), and the fused soup where members were
        // fused: the fusion answers to the median of the members, not to this energy.
        let mut rows = vec![("solution", rec.refined_soup.clone(), false)];
        if rec.report.ensemble.is_some() {
            rows.push(("solution fused", rec.soup.clone(), false));
        }
        rows.push(("truth", at(&oracle), true));
        if let (Some(flow), Some(depth12)) = (&case.flow12, &case.depth12) {
            let labels = &rec.superpixels.labels;
            let states = true_states(&rec.soup, labels, gt, flow, depth12, &k_in)?;
            rows.push(("true states", states, true));
        }
        println!();
        println!("| energy | state | E | refinement: w_proj E_proj + E_cont + E_ground | MRE |");
        println!("| --- | --- | --- | --- | --- |");
        for (name, mut soup, refined) in rows {
            for suffix in [Some(""), refined.then_some(" refined")]
                .into_iter()
                .flatten()
            {
                if !suffix.is_empty() {
                    refine::refine(&mut soup, &refine_problem, &inputs, &params.scales);
                }
                let terms = refine_problem.energy_terms(&soup);
                println!(
                    "| refine | {name}{suffix} | {:.3} | {:.3} + {:.3} + {:.3} | {:.4} |",
                    refine_problem.energy(&soup),
                    terms.proj,
                    terms.contacts,
                    terms.ground,
                    mre_of(&soup)?
                );
            }
        }
    }
    // Pieces carrying most of the error: solved depth / true depth after the global alignment,
    // from the final soup's own depths (the refinement moves planes too, so its λ alone does
    // not say how far a piece is off).
    let final_ratios = piece_log_ratios(rec, &rec.soup, gt, &k_in);
    let shift = median(final_ratios.iter().flatten().copied().collect());
    let mut rows: Vec<(f64, usize, f64)> = final_ratios
        .iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let ratio = exp(shift - (*r)?);
            let px = rec.superpixels.segments[i].pixels.len() as f64;
            Some(((ratio - 1.0).abs() * px, i, ratio))
        })
        .collect();
    rows.sort_by(|a, b| b.0.total_cmp(&a.0));
    let total: f64 = rows.iter().map(|r| r.0).sum::<f64>().max(1e-12);
    for &(weight, i, ratio) in rows.iter().take(5) {
        let piece = &rec.soup.pieces[i];
        let [x, y] = rec.superpixels.segments[i].anchor;
        println!(
            "  piece {i} at ({x:.0}, {y:.0}): depth {ratio:.2}× the truth, {:.0} % of the error, hypothesis {}{}",
            100.0 * weight / total,
            piece.hypothesis,
            if piece.degenerate.is_some() {
                ", degenerate"
            } else {
                ""
            }
        );
    }
    Ok(())
}

/// Per piece of the unit-scale soup, ln median(z_gt / z̄) over its pixels (input resolution,
/// nearest working-resolution label); `None` for a piece without valid ground truth.
fn piece_log_ratios(
    rec: &Reconstruction,
    soup: &Soup,
    gt: &Grid<f32>,
    k_in: &Intrinsics,
) -> Vec<Option<f64>> {
    let labels = &rec.superpixels.labels;
    let (w, h) = gt.size();
    let depth = depth_at(soup, labels, w, h, k_in);
    let key = |x: usize, y: usize| nearest_label(labels, w, h, x, y);
    oracle_ratios(&depth, gt, &key, soup.pieces.len())
        .into_iter()
        .map(|r| r.map(ln))
        .collect()
}

/// Per key (`key(x, y)` < `keys`: a superpixel, a ground-truth motion group), the oracle scale
/// median(z_gt / z) over its pixels with valid depths in both; `None` for a key without any.
fn oracle_ratios(
    unit: &Grid<f32>,
    gt: &Grid<f32>,
    key: &dyn Fn(usize, usize) -> usize,
    keys: usize,
) -> Vec<Option<f64>> {
    let mut ratios = vec![Vec::new(); keys];
    for y in 0..gt.height() {
        for x in 0..gt.width() {
            let (g, z) = (*gt.get(x, y), *unit.get(x, y));
            if g.is_finite() && g > 0.0 && z.is_finite() && z > 0.0 {
                ratios[key(x, y)].push(g as f64 / z as f64);
            }
        }
    }
    ratios
        .into_iter()
        .map(|r| (!r.is_empty()).then(|| median(r)))
        .collect()
}
