//! The files a reconstruction is saved as. The CLI's output folder (`soup reconstruct --out`) and
//! the web page's downloads both encode them here, so both give the same bytes.
//!
//! Maps are at the input resolution (the photos' own size), like the user's images: depth is
//! evaluated on each superpixel's plane at the input pixels' rays, the flow is resampled with its
//! vectors scaled. Point clouds and labels are at the working resolution (one point per pixel).

use crate::colormap::depth_picture;
use crate::error::{Error, Result};
use crate::flow::resize_flow;
use crate::formats::ply::{self, Encoding};
use crate::formats::{flo, pfm, png16};
use crate::image::encode_png;
use crate::output::cloud_labels;
use crate::pipeline::Reconstruction;

/// One output file of a reconstruction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFile {
    /// Frame-1 z-depth, PFM float32 (NaN = unknown), input resolution.
    DepthPfm,
    /// Frame-1 z-depth, 16-bit PNG with its scale in a `depth_scale` text chunk (0 = unknown),
    /// input resolution.
    DepthPng16,
    /// Frame-1 depth colour-mapped (near warm, far cool, unknown black), 8-bit RGB PNG.
    DepthPicture,
    /// Point cloud of frame 1 (X per pixel, camera-1 frame), PLY with colours.
    Frame1Ply,
    /// The same points in frame 2 (X' = R X + λ t̂), PLY with colours.
    Frame2Ply,
    /// The flow 1→2 used, Middlebury `.flo`, input resolution.
    Flow,
    /// Superpixel labels, 16-bit grey PNG, working resolution.
    Labels,
    /// The report (intrinsics and their source, sizes, parameters, timings, energies), JSON.
    Report,
}

impl ExportFile {
    /// Every file, in the order the CLI lists them.
    pub const ALL: [ExportFile; 8] = [
        ExportFile::DepthPfm,
        ExportFile::DepthPng16,
        ExportFile::DepthPicture,
        ExportFile::Frame1Ply,
        ExportFile::Frame2Ply,
        ExportFile::Flow,
        ExportFile::Labels,
        ExportFile::Report,
    ];

    /// The file's name in an output folder, and the page's download name.
    pub fn file_name(self) -> &'static str {
        match self {
            ExportFile::DepthPfm => "depth.pfm",
            ExportFile::DepthPng16 => "depth16.png",
            ExportFile::DepthPicture => "depth.png",
            ExportFile::Frame1Ply => "frame1.ply",
            ExportFile::Frame2Ply => "frame2.ply",
            ExportFile::Flow => "flow.flo",
            ExportFile::Labels => "labels.png",
            ExportFile::Report => "report.json",
        }
    }

    /// The file called `name` (one of the [`file_name`](Self::file_name)s).
    pub fn from_file_name(name: &str) -> Result<Self> {
        ExportFile::ALL
            .into_iter()
            .find(|f| f.file_name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = ExportFile::ALL.iter().map(|f| f.file_name()).collect();
                Error::InvalidParameter(format!(
                    "unknown output file {name:?}; choose one of {}",
                    names.join(", ")
                ))
            })
    }

    /// The media type a browser download gets.
    pub fn media_type(self) -> &'static str {
        match self {
            ExportFile::DepthPng16 | ExportFile::DepthPicture | ExportFile::Labels => "image/png",
            ExportFile::Report => "application/json",
            ExportFile::Frame1Ply | ExportFile::Frame2Ply => "application/x-ply",
            ExportFile::DepthPfm | ExportFile::Flow => "application/octet-stream",
        }
    }
}

/// The bytes of `file` for reconstruction `rec`; PLY bodies use `ply_encoding`.
pub fn encode(rec: &Reconstruction, file: ExportFile, ply_encoding: Encoding) -> Result<Vec<u8>> {
    let (input_w, input_h) = rec.report.input_size;
    match file {
        ExportFile::DepthPfm => Ok(pfm::encode(&rec.depth_input)),
        ExportFile::DepthPng16 => png16::encode_depth(&rec.depth_input),
        ExportFile::DepthPicture => encode_png(&depth_picture(&rec.depth_input)),
        ExportFile::Frame1Ply | ExportFile::Frame2Ply => {
            let (cloud1, cloud2) = rec.clouds();
            let cloud = if file == ExportFile::Frame1Ply {
                cloud1
            } else {
                cloud2
            };
            ply::encode_with_confidence(&cloud, Some(&point_confidence(rec)), ply_encoding)
        }
        ExportFile::Flow => Ok(flo::encode(&resize_flow(&rec.flow, input_w, input_h))),
        ExportFile::Labels => png16::encode_labels(&rec.superpixels.labels),
        ExportFile::Report => report_json(rec),
    }
}

/// The scale confidence (report `confidence`, in [0, 1]) of each point of the clouds: that of
/// the point's superpixel (NaN for a label the report does not cover).
fn point_confidence(rec: &Reconstruction) -> Vec<f32> {
    cloud_labels(&rec.superpixels.labels, &rec.depth)
        .iter()
        .map(|&label| {
            rec.report
                .confidence
                .get(label as usize)
                .map_or(f32::NAN, |&c| c as f32)
        })
        .collect()
}

/// The report as pretty-printed JSON.
pub fn report_json(rec: &Reconstruction) -> Result<Vec<u8>> {
    serde_json::to_vec_pretty(&rec.report).map_err(|e| Error::format("JSON", e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_are_distinct_and_round_trip() {
        for file in ExportFile::ALL {
            assert_eq!(ExportFile::from_file_name(file.file_name()).unwrap(), file);
        }
        let mut names: Vec<&str> = ExportFile::ALL.iter().map(|f| f.file_name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), ExportFile::ALL.len());
        let err = ExportFile::from_file_name("depth.exr").unwrap_err();
        assert!(err.to_string().contains("frame1.ply"), "{err}");
    }
}
