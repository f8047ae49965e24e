//! `soup superpixels`: SLIC superpixels of one image, as a 16-bit label PNG and pictures.

use std::path::PathBuf;
use std::time::Instant;

use superpixel_soup::Result;
use superpixel_soup::formats::{png16, write_file};
use superpixel_soup::image::{encode_png, read_image_file};
use superpixel_soup::superpixels::view::{boundary_overlay, mean_colour};
use superpixel_soup::superpixels::{SlicParams, slic};

/// Segment an image into SLIC superpixels.
#[derive(clap::Args)]
pub struct Args {
    /// The image (PNG or JPEG), segmented at its own resolution.
    frame: PathBuf,
    /// Requested number of superpixels (the result is within a few percent of it).
    #[arg(long, default_value_t = SlicParams::default().count)]
    n: usize,
    /// Compactness m: weight of spatial against colour distance; larger gives more regular, less
    /// colour-driven superpixels.
    #[arg(long, default_value_t = SlicParams::default().compactness)]
    compactness: f32,
    /// Where to write the labels (16-bit greyscale PNG, label = pixel value).
    #[arg(long)]
    out: PathBuf,
    /// Also write the image with superpixel boundaries drawn in yellow.
    #[arg(long)]
    overlay: Option<PathBuf>,
    /// Also write each superpixel painted with its mean colour.
    #[arg(long)]
    mean: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let frame = read_image_file(&args.frame)?.frame;
    let params = SlicParams {
        count: args.n,
        compactness: args.compactness,
        ..SlicParams::default()
    };
    let start = Instant::now();
    let sp = slic(&frame, &params)?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    write_file(&args.out, &png16::encode_labels(&sp.labels)?)?;
    if let Some(path) = &args.overlay {
        write_file(
            path,
            &encode_png(&boundary_overlay(&frame, &sp, [255, 230, 0]))?,
        )?;
    }
    if let Some(path) = &args.mean {
        write_file(path, &encode_png(&mean_colour(&sp))?)?;
    }
    let smallest = sp.smallest_size();
    println!(
        "{} superpixels (requested {}), smallest {smallest} pixels, {ms:.0} ms",
        sp.len(),
        args.n
    );
    Ok(())
}
