//! The evaluation case layout (the public cases [`crate::eval::eval_case_dir`] finds are in it, and
//! `soup synth` writes it): a folder holding `frame1.png`, `frame2.png`, optional `intrinsics.txt`
//! (`fx fy cx cy`), `depth1.pfm` (z-depth of frame 1, NaN = unknown; or `depth1.dpt`, MPI Sintel's
//! format) and `flow12.flo`. Our synthetic scenes add `depth12.pfm` (z-depth in camera 2 of frame
//! 1's surface point at each frame-1 pixel: with `depth1` and `flow12` the scene flow),
//! `moving1.png` (255 where the surface moves in the world) and `groups1.png` (motion group per
//! pixel: 0 = static world, 1.. = each independent motion).

use std::path::{Path, PathBuf};

use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use crate::flow::FlowField;
use crate::grid::Grid;
use crate::image::{Frame, decode_image, encode_png};

use super::{dpt, flo, pfm, png16, read_file, write_file};

/// One evaluation case: two frames and whatever ground truth it has.
#[derive(Clone, Debug)]
pub struct Case {
    /// Folder name, for tables.
    pub name: String,
    pub frame1: Frame,
    pub frame2: Frame,
    pub intrinsics: Option<Intrinsics>,
    pub depth1: Option<Grid<f32>>,
    pub flow12: Option<FlowField>,
    /// z-depth in camera 2 of frame 1's surface point at each frame-1 pixel (synthetic scenes:
    /// with `depth1` and `flow12`, the exact scene flow).
    pub depth12: Option<Grid<f32>>,
    pub moving1: Option<Grid<bool>>,
    pub groups1: Option<Grid<u8>>,
}

/// Reads a case folder; frames are required, everything else optional. Every present file must
/// parse and match frame 1's size.
pub fn read_case(dir: &Path) -> Result<Case> {
    let frame = |name: &str| -> Result<Frame> {
        let path = dir.join(name);
        decode_image(&read_file(&path)?)
            .map(|img| img.frame)
            .map_err(|e| with_path(&path, e))
    };
    let frame1 = frame("frame1.png")?;
    let frame2 = frame("frame2.png")?;
    frame1.check_same_size(&frame2)?;
    let intrinsics = optional(dir, "intrinsics.txt", |b| {
        Intrinsics::parse(&String::from_utf8_lossy(b))
    })?;
    let depth1 = match optional(dir, "depth1.pfm", pfm::decode)? {
        Some(depth) => Some(depth),
        None => optional(dir, "depth1.dpt", dpt::decode)?,
    };
    let flow12 = optional(dir, "flow12.flo", flo::decode)?;
    let depth12 = optional(dir, "depth12.pfm", pfm::decode)?;
    let moving1 = optional(dir, "moving1.png", |b| {
        Ok(png16::decode(b)?.0.map(|&v| v > 0))
    })?;
    let groups1 = optional(dir, "groups1.png", |b| {
        Ok(png16::decode(b)?.0.map(|&v| v.min(255) as u8))
    })?;
    let sizes = [
        depth1.as_ref().map(Grid::size),
        flow12.as_ref().map(Grid::size),
        depth12.as_ref().map(Grid::size),
        moving1.as_ref().map(Grid::size),
        groups1.as_ref().map(Grid::size),
    ];
    if let Some((w, h)) = sizes.into_iter().flatten().find(|&s| s != frame1.size()) {
        return Err(Error::format(
            "case",
            format!(
                "{}: ground truth is {w}×{h} but frame 1 is {}×{}",
                dir.display(),
                frame1.width(),
                frame1.height()
            ),
        ));
    }
    Ok(Case {
        name: case_name(dir),
        frame1,
        frame2,
        intrinsics,
        depth1,
        flow12,
        depth12,
        moving1,
        groups1,
    })
}

/// Writes a case folder (created if missing); absent parts are not written.
pub fn write_case(dir: &Path, case: &Case) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_file(&dir.join("frame1.png"), &encode_png(&case.frame1)?)?;
    write_file(&dir.join("frame2.png"), &encode_png(&case.frame2)?)?;
    if let Some(k) = &case.intrinsics {
        write_file(
            &dir.join("intrinsics.txt"),
            format!("{}\n", k.to_line()).as_bytes(),
        )?;
    }
    if let Some(depth) = &case.depth1 {
        write_file(&dir.join("depth1.pfm"), &pfm::encode(depth))?;
    }
    if let Some(flow) = &case.flow12 {
        write_file(&dir.join("flow12.flo"), &flo::encode(flow))?;
    }
    if let Some(depth) = &case.depth12 {
        write_file(&dir.join("depth12.pfm"), &pfm::encode(depth))?;
    }
    if let Some(moving) = &case.moving1 {
        let mask = moving.map(|&m| if m { 255u16 } else { 0 });
        write_file(&dir.join("moving1.png"), &png16::encode(&mask, &[])?)?;
    }
    if let Some(groups) = &case.groups1 {
        write_file(
            &dir.join("groups1.png"),
            &png16::encode(&groups.map(|&g| g as u16), &[])?,
        )?;
    }
    Ok(())
}

/// Reads an optional file of a case with `parse`; `None` when it does not exist.
fn optional<T>(
    dir: &Path,
    name: &str,
    parse: impl FnOnce(&[u8]) -> Result<T>,
) -> Result<Option<T>> {
    let path = dir.join(name);
    if !path.exists() {
        return Ok(None);
    }
    let bytes = read_file(&path)?;
    parse(&bytes).map(Some).map_err(|e| with_path(&path, e))
}

/// Prefixes format and decode errors with the file they concern.
fn with_path(path: &Path, e: Error) -> Error {
    match e {
        Error::Format { format, reason } => Error::Format {
            format,
            reason: format!("{}: {reason}", path.display()),
        },
        Error::Decode(reason) => Error::Decode(format!("{}: {reason}", path.display())),
        Error::InvalidParameter(reason) => {
            Error::InvalidParameter(format!("{}: {reason}", path.display()))
        }
        other => other,
    }
}

fn case_name(dir: &Path) -> String {
    let canonical: PathBuf = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    canonical
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| dir.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("soup-case-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn sample_case() -> Case {
        let frame = Grid::from_fn(40, 33, |x, y| [(x * 6) as u8, (y * 7) as u8, 99]);
        Case {
            name: "sample".into(),
            frame1: frame.clone(),
            frame2: frame,
            intrinsics: Some(Intrinsics {
                fx: 50.0,
                fy: 51.0,
                cx: 19.5,
                cy: 16.0,
            }),
            depth1: Some(Grid::from_fn(40, 33, |x, _| 1.0 + x as f32)),
            flow12: Some(Grid::filled(40, 33, [0.5, -1.0])),
            depth12: Some(Grid::from_fn(40, 33, |_, y| 2.0 + y as f32)),
            moving1: Some(Grid::from_fn(40, 33, |x, _| x > 20)),
            groups1: Some(Grid::from_fn(40, 33, |x, _| (x > 20) as u8 * 3)),
        }
    }

    #[test]
    fn round_trip_of_every_file() {
        let dir = temp_dir("round-trip");
        let case = sample_case();
        write_case(&dir, &case).unwrap();
        let back = read_case(&dir).unwrap();
        assert_eq!(back.frame1, case.frame1);
        assert_eq!(back.intrinsics, case.intrinsics);
        assert_eq!(back.depth1, case.depth1);
        assert_eq!(back.flow12, case.flow12);
        assert_eq!(back.depth12, case.depth12);
        assert_eq!(back.moving1, case.moving1);
        assert_eq!(back.groups1, case.groups1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_sintel_dpt_depth_is_read_when_there_is_no_pfm() {
        let dir = temp_dir("dpt");
        let case = sample_case();
        write_case(&dir, &case).unwrap();
        std::fs::remove_file(dir.join("depth1.pfm")).unwrap();
        let depth = case.depth1.as_ref().unwrap();
        write_file(&dir.join("depth1.dpt"), &dpt::encode(depth)).unwrap();
        assert_eq!(read_case(&dir).unwrap().depth1.as_ref(), Some(depth));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_frames_and_bad_files_name_the_path() {
        let dir = temp_dir("bad");
        let err = read_case(&dir).unwrap_err().to_string();
        assert!(err.contains("frame1.png"), "{err}");
        write_case(&dir, &sample_case()).unwrap();
        std::fs::write(dir.join("depth1.pfm"), b"Pf\n3 3\n-1\n").unwrap();
        let err = read_case(&dir).unwrap_err().to_string();
        assert!(err.contains("depth1.pfm"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reads_the_public_eval_case_when_present() {
        let Some(root) = crate::eval::eval_case_dir("middlebury-motorcycle") else {
            eprintln!("skipping: the evaluation case middlebury-motorcycle is absent");
            return;
        };
        let case = read_case(&root).unwrap();
        assert_eq!(case.frame1.size(), (741, 500));
        assert!(case.intrinsics.is_some() && case.depth1.is_some() && case.flow12.is_some());
    }
}
