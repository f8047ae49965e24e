//! The `soup` command line: what it writes, and one readable line plus a non-zero exit on errors.
#![cfg(not(target_arch = "wasm32"))]

use std::path::PathBuf;
use std::process::{Command, Output};

use superpixel_soup::export::ExportFile;
use superpixel_soup::formats::case::read_case;

fn soup(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_soup"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `soup` with `args` and fails the test, showing its stderr, unless it succeeds.
fn soup_ok(args: &[&str]) -> Output {
    let out = soup(args);
    assert!(
        out.status.success(),
        "soup {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("soup-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Renders `scene` at `size` ("WxH") with `soup synth` into `dir`; returns the case folder.
fn synth_scene(dir: &std::path::Path, scene: &str, size: &str) -> PathBuf {
    soup_ok(&[
        "synth",
        dir.to_str().unwrap(),
        "--scene",
        scene,
        "--size",
        size,
    ]);
    dir.join(scene)
}

#[test]
fn synth_writes_every_scene_in_the_case_layout() {
    let dir = temp_dir("synth");
    soup_ok(&[
        "synth",
        dir.to_str().unwrap(),
        "--size",
        "96x48",
        "--preview",
    ]);
    for name in ["static-room", "street", "crowd", "flag"] {
        let case = read_case(&dir.join(name)).unwrap();
        assert_eq!(case.frame1.size(), (96, 48));
        assert!(case.intrinsics.is_some() && case.depth1.is_some() && case.flow12.is_some());
        assert!(
            case.depth12.is_some(),
            "{name}: no scene flow (depth12.pfm)"
        );
        assert!(case.moving1.is_some() && case.groups1.is_some());
        assert!(dir.join(name).join("preview.png").exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn errors_are_one_line_and_exit_non_zero() {
    let dir = temp_dir("errors");
    for (args, expected) in [
        (
            vec!["synth", dir.to_str().unwrap(), "--scene", "moon"],
            "unknown scene",
        ),
        (
            vec!["synth", dir.to_str().unwrap(), "--size", "8x8"],
            "16 and",
        ),
        (
            vec![
                "synth",
                "/proc/soup-cannot-write-here",
                "--scene",
                "flag",
                "--size",
                "32x32",
            ],
            "soup-cannot-write-here",
        ),
    ] {
        let out = soup(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} should fail");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    let out = soup(&["synth", dir.to_str().unwrap(), "--size", "big"]);
    assert!(!out.status.success());
}

#[test]
fn reconstruct_writes_the_documented_files() {
    let dir = temp_dir("reconstruct");
    let case = synth_scene(&dir, "static-room", "256x110");
    let intrinsics = std::fs::read_to_string(case.join("intrinsics.txt")).unwrap();
    let result = dir.join("result");
    let path = |name: &str| case.join(name).to_str().unwrap().to_string();
    soup_ok(&[
        "reconstruct",
        &path("frame1.png"),
        &path("frame2.png"),
        "--flow",
        &path("flow12.flo"),
        "--intrinsics",
        intrinsics.trim(),
        "--superpixels",
        "150",
        "--out",
        result.to_str().unwrap(),
    ]);
    for name in [
        "depth.pfm",
        "depth16.png",
        "depth.png",
        "frame1.ply",
        "frame2.ply",
        "flow.flo",
        "labels.png",
        "report.json",
    ] {
        assert!(result.join(name).exists(), "{name} missing");
    }
    let depth =
        superpixel_soup::formats::pfm::decode(&std::fs::read(result.join("depth.pfm")).unwrap())
            .unwrap();
    assert_eq!(depth.size(), (256, 110));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(result.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["camera"]["source"], "user");
    // Four members fused by default, from counts 1/15 and 2/15 either side of the 150 asked.
    assert_eq!(
        report["ensemble"]["counts"],
        serde_json::json!([140, 160, 130, 170])
    );
    assert_eq!(report["ensemble"]["failed"], serde_json::json!([]));
    assert!(report["ensemble"]["rescaled"].as_u64().unwrap() < 150);
    // Without a flow file the flow is computed; the report records its parameters. (Kept at the
    // preset asked for: at this size less than 75 % of the fast flow passes its check, which
    // would have it computed again with the next preset, and no second pass is asked for where
    // too few scales are pinned, the camera's motion is ambiguous or no ground is found.)
    let computed = dir.join("computed");
    let keep_preset = dir.join("keep-preset.json");
    std::fs::write(
        &keep_preset,
        r#"{"min_reliable_flow": 0.0, "min_pinned_share": 0.0, "finer_without_ground": false, "init": {"ambiguous_ego_excess": 0.0}}"#,
    )
    .unwrap();
    soup_ok(&[
        "reconstruct",
        &path("frame1.png"),
        &path("frame2.png"),
        "--intrinsics",
        intrinsics.trim(),
        "--superpixels",
        "150",
        "--preset",
        "fast",
        "--members",
        "1",
        "--params",
        keep_preset.to_str().unwrap(),
        "--out",
        computed.to_str().unwrap(),
    ]);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(computed.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["flow"]["dis"]["finest_level"], 2);
    // `--members 1` turns the fusion off.
    assert_eq!(report["ensemble"], serde_json::Value::Null);
    assert_eq!(report["notes"], serde_json::json!([]));
    assert!(report["reliable_flow"].as_f64().unwrap() > 0.5);
    let flow =
        superpixel_soup::formats::flo::decode(&std::fs::read(computed.join("flow.flo")).unwrap())
            .unwrap();
    assert_eq!(flow.size(), (256, 110));
    let out = soup(&[
        "reconstruct",
        &path("frame1.png"),
        &path("frame2.png"),
        "--preset",
        "slow",
        "--out",
        computed.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown flow preset"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn flow_writes_both_fields_and_a_picture_and_scores_cases() {
    let dir = temp_dir("flow");
    let case = synth_scene(&dir, "street", "192x96");
    let path = |name: &str| case.join(name).to_str().unwrap().to_string();
    let (forward, backward, viz) = (dir.join("f.flo"), dir.join("b.flo"), dir.join("f.png"));
    soup_ok(&[
        "flow",
        &path("frame1.png"),
        &path("frame2.png"),
        "--out",
        forward.to_str().unwrap(),
        "--backward",
        backward.to_str().unwrap(),
        "--viz",
        viz.to_str().unwrap(),
    ]);
    let read_flo =
        |p: &PathBuf| superpixel_soup::formats::flo::decode(&std::fs::read(p).unwrap()).unwrap();
    assert_eq!(read_flo(&forward).size(), (192, 96));
    assert_eq!(read_flo(&backward).size(), (192, 96));
    let picture = superpixel_soup::image::read_image_file(&viz).unwrap().frame;
    assert_eq!(picture.size(), (192, 96));

    // --eval prints one table row per case with its EPE.
    let out = soup_ok(&["flow", "--eval", case.to_str().unwrap(), "--preset", "fast"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let row = stdout
        .lines()
        .find(|l| l.starts_with("| street |"))
        .unwrap_or_else(|| panic!("no row for street in {stdout}"));
    let epe: f64 = row.split('|').nth(3).unwrap().trim().parse().unwrap();
    assert!(epe < 2.0, "{row}");

    // Errors: one line, non-zero exit.
    let other = dir.join("other.png");
    let small = superpixel_soup::grid::Grid::filled(50, 40, [9u8, 9, 9]);
    std::fs::write(&other, superpixel_soup::image::encode_png(&small).unwrap()).unwrap();
    let (frame1, frame2) = (path("frame1.png"), path("frame2.png"));
    let forward = forward.to_str().unwrap();
    for (args, expected) in [
        (
            vec!["flow", &frame1, other.to_str().unwrap(), "--out", forward],
            "differ in size",
        ),
        (vec!["flow", &frame1], "two frames"),
        (vec!["flow", &frame1, &frame2], "--out"),
    ] {
        let out = soup(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} should fail");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn superpixels_writes_labels_and_pictures() {
    let dir = temp_dir("superpixels");
    let frame = synth_scene(&dir, "street", "128x64").join("frame1.png");
    let file = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let out = soup_ok(&[
        "superpixels",
        frame.to_str().unwrap(),
        "--n",
        "40",
        "--compactness",
        "12",
        "--out",
        &file("labels.png"),
        "--overlay",
        &file("overlay.png"),
        "--mean",
        &file("mean.png"),
    ]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("superpixels (requested 40)"));
    let (labels, _) =
        superpixel_soup::formats::png16::decode(&std::fs::read(file("labels.png")).unwrap())
            .unwrap();
    assert_eq!(labels.size(), (128, 64));
    let count = *labels.data().iter().max().unwrap() as usize + 1;
    assert!((34..=46).contains(&count), "{count} superpixels");
    for picture in ["overlay.png", "mean.png"] {
        let image = superpixel_soup::image::read_image_file(&dir.join(picture)).unwrap();
        assert_eq!(image.frame.size(), (128, 64), "{picture}");
    }
    // Bad requests fail with one readable line.
    let out = soup(&[
        "superpixels",
        frame.to_str().unwrap(),
        "--n",
        "5000",
        "--out",
        &file("labels.png"),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("superpixel count"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_fresh_process_writes_the_same_files() {
    // The whole pipeline with computed flow, run twice in separate processes: flow, SLIC and the
    // seeded RANSAC of the soup must not depend on anything that changes between runs (hash
    // seeds, addresses, the clock), so every output is byte for byte the same; only the
    // report's timings may differ.
    // The flag, because its many motion hypotheses make the result depend on the RANSAC
    // samples: with the seed changed per process its outputs differ (the street's happen not to).
    let dir = temp_dir("fresh-process");
    let case = synth_scene(&dir, "flag", "256x110");
    let path = |name: &str| case.join(name).to_str().unwrap().to_string();
    let run = |name: &str| {
        let result = dir.join(name);
        soup_ok(&[
            "reconstruct",
            &path("frame1.png"),
            &path("frame2.png"),
            "--superpixels",
            "150",
            "--preset",
            "fast",
            "--out",
            result.to_str().unwrap(),
        ]);
        result
    };
    let (first, second) = (run("first"), run("second"));
    let mut compared = 0;
    for entry in std::fs::read_dir(&first).unwrap() {
        let name = entry.unwrap().file_name();
        let (a, b) = (
            std::fs::read(first.join(&name)).unwrap(),
            std::fs::read(second.join(&name)).unwrap(),
        );
        if name == "report.json" {
            let without_timings = |bytes: &[u8]| {
                let mut report: serde_json::Value = serde_json::from_slice(bytes).unwrap();
                report.as_object_mut().unwrap().remove("timings_ms");
                report
            };
            assert_eq!(without_timings(&a), without_timings(&b));
        } else {
            assert!(a == b, "{name:?} differs between two runs");
        }
        compared += 1;
    }
    assert_eq!(
        compared,
        ExportFile::ALL.len(),
        "every output file compared"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn help_shows_the_library_defaults() {
    // The defaults `--help` shows are the library's, not copies that could drift from it.
    let params = superpixel_soup::Params::default();
    let out = soup_ok(&["reconstruct", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    let preset = superpixel_soup::flow::Preset::default();
    for (option, default) in [
        ("--preset", preset.name().to_string()),
        ("--superpixels", params.superpixels.count.to_string()),
        ("--compactness", params.superpixels.compactness.to_string()),
        ("--k", params.k.to_string()),
        ("--members", params.ensemble.members.to_string()),
    ] {
        let section = help
            .split(&format!("{option} <"))
            .nth(1)
            .unwrap_or_else(|| panic!("{option} missing from:\n{help}"));
        let shown = section.split("[default: ").nth(1).unwrap();
        assert_eq!(shown.split(']').next().unwrap(), default, "{option}");
    }
    // Parameters without an option are listed with their defaults too.
    let listed = help.split_once('{').map(|(_, rest)| format!("{{{rest}"));
    let listed: serde_json::Value = serde_json::from_str(listed.as_deref().unwrap()).unwrap();
    assert_eq!(listed, serde_json::to_value(params).unwrap());
}

#[test]
fn a_params_file_sets_parameters_and_rejects_unknown_ones() {
    let dir = temp_dir("params");
    let case = synth_scene(&dir, "static-room", "256x110");
    let intrinsics = std::fs::read_to_string(case.join("intrinsics.txt")).unwrap();
    let path = |name: &str| case.join(name).to_str().unwrap().to_string();
    let run = |params: &str| {
        let file = dir.join("params.json");
        std::fs::write(&file, params).unwrap();
        let result = dir.join("result");
        let out = soup(&[
            "reconstruct",
            &path("frame1.png"),
            &path("frame2.png"),
            "--flow",
            &path("flow12.flo"),
            "--intrinsics",
            intrinsics.trim(),
            "--params",
            file.to_str().unwrap(),
            "--out",
            result.to_str().unwrap(),
        ]);
        let report = std::fs::read(result.join("report.json")).unwrap_or_default();
        (
            out,
            serde_json::from_slice::<serde_json::Value>(&report).ok(),
        )
    };
    // A nested field set, the others kept, recorded in the report.
    let (out, report) = run(r#"{"superpixels": {"count": 120}, "refine": {"iterations": 2}}"#);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = report.unwrap();
    assert_eq!(report["params"]["superpixels"]["count"], 120);
    assert_eq!(report["params"]["refine"]["iterations"], 2);
    assert_eq!(report["refine"]["energies"].as_array().unwrap().len(), 3);
    assert_eq!(
        report["params"]["refine"]["particles"],
        superpixel_soup::Params::default().refine.particles
    );
    // A typo is an error naming the field, not silently ignored.
    let (out, _) = run(r#"{"refine": {"iteratons": 2}}"#);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown parameter refine.iteratons"), "{err}");
}

/// The truth test's tables (`soup eval --oracle`) of the synthetic `scene` at 512×218 with 600
/// superpixels and exact flow, written under `dir`.
fn truth_test_of(dir: &std::path::Path, scene: &str) -> String {
    let case = synth_scene(dir, scene, "512x218");
    let out = soup_ok(&[
        "eval",
        case.to_str().unwrap(),
        "--gt-flow",
        "--superpixels",
        "600",
        "--oracle",
    ]);
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Column `column` (the `|`-separated field, 1 = the energy's name) of the truth test's row for
/// `energy` ("scales" or "refine") and `state` in `text`.
fn truth_test_value(text: &str, energy: &str, state: &str, column: usize) -> f64 {
    let row = text
        .lines()
        .find(|l| l.starts_with(&format!("| {energy} | {state} |")))
        .unwrap_or_else(|| panic!("no {energy} {state} row in:\n{text}"));
    row.split('|').nth(column).unwrap().trim().parse().unwrap()
}

#[test]
fn truth_test_the_scale_energy_ranks_the_polished_truth_below_the_solution() {
    // `soup eval --oracle`: the scale energy at the scale solve's answer and at the ground truth
    // (each superpixel at its oracle scale) polished by the per-piece descent: the issue's check
    // (the truth-polished energy below the solution's), on a static and a dynamic scene (the
    // street's cars move on their own), exact flow. It does not show that the energy prefers
    // the truth's basin: the same descent from the solution ends at or below the polished truth
    // (at this size static-room 5.727 both, street 3.791 against 3.839; docs/RESULTS.md, "the
    // fair truth test"), so the test also reads that row: the descent never raises the energy.
    let dir = temp_dir("truth-test");
    for scene in ["static-room", "street"] {
        let text = truth_test_of(&dir, scene);
        let solution = truth_test_value(&text, "scales", "scale solve", 3);
        let truth = truth_test_value(&text, "scales", "truth polished", 3);
        assert!(
            truth < solution,
            "{scene}: polished truth {truth} not below the solution {solution}"
        );
        let polished = truth_test_value(&text, "scales", "scale solve polished", 3);
        assert!(
            polished <= solution,
            "{scene}: the descent raised the solution's energy {solution} to {polished}"
        );
    }
}

#[test]
fn truth_test_the_refinement_energy_ranks_the_true_states_below_the_solution_on_movers() {
    // `soup eval --oracle` on a case with scene flow (`depth12.pfm`, written by `soup synth`):
    // every piece at its true rigid motion and plane, then refined by the same optimiser. On a
    // crowd and a bending flag the refinement's energy of that state is well below the
    // solution's, which keeps its pieces on shared motion hypotheses (measured at 512×218, 600
    // superpixels, exact flow: crowd 15.5 against 38.1, flag 34.5 against 48.8; the true states'
    // MRE 0.0033 and 0.0072): the energy has a state near the truth below the solution's, and
    // the optimiser does not reach it.
    let dir = temp_dir("true-states");
    for scene in ["crowd", "flag"] {
        let text = truth_test_of(&dir, scene);
        let solution = truth_test_value(&text, "refine", "solution", 3);
        let truth = truth_test_value(&text, "refine", "true states refined", 3);
        assert!(
            truth < 0.85 * solution,
            "{scene}: true states refined {truth} not well below the solution {solution}"
        );
        // The true states are the truth: their depth is almost exact.
        let mre = truth_test_value(&text, "refine", "true states", 5);
        assert!(mre < 0.01, "{scene}: true states' MRE {mre}");
    }
}

#[test]
fn eval_groups_splits_the_error_by_ground_truth_group() {
    // `soup eval --groups` on a case with motion groups (groups1.png): one row per ground-truth
    // group. Its pixels partition the valid pixels and its MRE shares add up to the case's MRE.
    // With exact flow the street's static world (group 0) lies on the ego-motion and at its
    // true depth (ratio within 2 % of 1 after the global median alignment; 1.000 measured at
    // this size), and each of its two cars has a row; the ego-motion's error is reported.
    let dir = temp_dir("eval-groups");
    let case = synth_scene(&dir, "street", "512x218");
    let json = dir.join("eval.json");
    let out = soup_ok(&[
        "eval",
        case.to_str().unwrap(),
        "--gt-flow",
        "--superpixels",
        "600",
        "--groups",
        "--json",
        json.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    // group, pixels, MRE, depth ratio, MRE share, main hypothesis, its share.
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip_while(|l| !l.starts_with("| GT group |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            l.split(['|', '(', ')'])
                .map(str::trim)
                .filter(|c| !c.is_empty())
                .map(|c| c.parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 3, "one row per group expected in:\n{text}");
    let result: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let metrics = &result[0]["metrics"];
    let pixels: f64 = rows.iter().map(|r| r[1]).sum();
    assert_eq!(pixels, metrics["pixels"].as_f64().unwrap());
    let shares: f64 = rows.iter().map(|r| r[4]).sum();
    let mre = metrics["mre"].as_f64().unwrap();
    assert!(
        (shares - mre).abs() < 0.001,
        "shares {shares} against MRE {mre}"
    );
    let world = &rows[0];
    assert_eq!(world[0], 0.0);
    assert!(
        (world[3] - 1.0).abs() < 0.02,
        "static world's ratio {}",
        world[3]
    );
    assert!(
        world[5] == 0.0 && world[6] >= 0.95,
        "static world on {world:?}"
    );
    // The ego-motion against the camera's true motion (the still pixels' scene flow): exact
    // flow finds it within 0.005° here (a compromise with the cars would be degrees off).
    let ego = &result[0]["ego_error"];
    let (t, r) = (
        ego["translation_deg"].as_f64(),
        ego["rotation_deg"].as_f64(),
    );
    assert!(
        t.is_some_and(|t| t < 0.5) && r.is_some_and(|r| r < 0.05),
        "ego-motion error {ego}"
    );
}
