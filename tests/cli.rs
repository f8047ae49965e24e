//! The `soup` command line: what it writes, and one readable line plus a non-zero exit on errors.
#![cfg(not(target_arch = "wasm32"))]

use std::path::PathBuf;
use std::process::{Command, Output};

use superpixel_soup::formats::case::read_case;

fn soup(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_soup"))
        .args(args)
        .output()
        .unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("soup-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn synth_writes_every_scene_in_the_case_layout() {
    let dir = temp_dir("synth");
    let out = soup(&[
        "synth",
        dir.to_str().unwrap(),
        "--size",
        "96x48",
        "--preview",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in ["static-room", "street", "crowd", "flag"] {
        let case = read_case(&dir.join(name)).unwrap();
        assert_eq!(case.frame1.size(), (96, 48));
        assert!(case.intrinsics.is_some() && case.depth1.is_some() && case.flow12.is_some());
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
    let out = soup(&[
        "synth",
        dir.to_str().unwrap(),
        "--scene",
        "static-room",
        "--size",
        "256x110",
    ]);
    assert!(out.status.success());
    let case = dir.join("static-room");
    let intrinsics = std::fs::read_to_string(case.join("intrinsics.txt")).unwrap();
    let result = dir.join("result");
    let path = |name: &str| case.join(name).to_str().unwrap().to_string();
    let out = soup(&[
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
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in [
        "depth.pfm",
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
    // Without a flow file the command says what is missing.
    let out = soup(&[
        "reconstruct",
        &path("frame1.png"),
        &path("frame2.png"),
        "--out",
        result.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--flow"));
    std::fs::remove_dir_all(&dir).unwrap();
}
