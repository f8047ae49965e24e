//! PLY point clouds with per-vertex colour: `x y z` (float) and `red green blue` (uchar), and
//! optionally `confidence` (float: the scale confidence of the point's superpixel, in [0, 1]).
//! Written as binary little-endian by default, ASCII on request; read back from either, and from
//! other tools' files whose vertex element has those properties among others.

use crate::error::{Error, Result};
use crate::output::PointCloud;

/// PLY body encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    BinaryLittleEndian,
    Ascii,
}

/// Encodes a cloud. Points with a non-finite coordinate are skipped (PLY has no "unknown").
pub fn encode(cloud: &PointCloud, encoding: Encoding) -> Result<Vec<u8>> {
    encode_with_confidence(cloud, None, encoding)
}

/// Encodes a cloud with a `confidence` float property per vertex (`confidence[i]` for point
/// `i`), when given. Points with a non-finite coordinate are skipped. Fails when the lengths
/// disagree.
pub fn encode_with_confidence(
    cloud: &PointCloud,
    confidence: Option<&[f32]>,
    encoding: Encoding,
) -> Result<Vec<u8>> {
    if let Some(confidence) = confidence
        && confidence.len() != cloud.positions.len()
    {
        return Err(Error::InvalidParameter(format!(
            "point cloud has {} positions but {} confidences",
            cloud.positions.len(),
            confidence.len()
        )));
    }
    if cloud.positions.len() != cloud.colours.len() {
        return Err(Error::InvalidParameter(format!(
            "point cloud has {} positions but {} colours",
            cloud.positions.len(),
            cloud.colours.len()
        )));
    }
    let points: Vec<([f32; 3], [u8; 3], Option<f32>)> = cloud
        .positions
        .iter()
        .zip(&cloud.colours)
        .enumerate()
        .filter(|(_, (p, _))| p.iter().all(|c| c.is_finite()))
        .map(|(i, (p, c))| (*p, *c, confidence.map(|k| k[i])))
        .collect();
    let format = match encoding {
        Encoding::BinaryLittleEndian => "binary_little_endian",
        Encoding::Ascii => "ascii",
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment written by superpixel-soup\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n{}end_header\n",
        points.len(),
        if confidence.is_some() {
            "property float confidence\n"
        } else {
            ""
        }
    )
    .into_bytes();
    for (p, c, k) in points {
        match encoding {
            Encoding::BinaryLittleEndian => {
                for v in p {
                    out.extend_from_slice(&v.to_le_bytes());
                }
                out.extend_from_slice(&c);
                if let Some(k) = k {
                    out.extend_from_slice(&k.to_le_bytes());
                }
            }
            Encoding::Ascii => {
                out.extend_from_slice(
                    format!("{} {} {} {} {} {}", p[0], p[1], p[2], c[0], c[1], c[2]).as_bytes(),
                );
                if let Some(k) = k {
                    out.extend_from_slice(format!(" {k}").as_bytes());
                }
                out.push(b'\n');
            }
        }
    }
    Ok(out)
}

/// A scalar property type of the PLY format.
#[derive(Clone, Copy, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// Reads one little-endian value (caller checks bounds).
    fn read_le(self, b: &[u8]) -> f64 {
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }
}

/// What the header says about the vertex element.
struct Header {
    encoding: Encoding,
    vertices: usize,
    properties: Vec<(String, Scalar)>,
    body_start: usize,
}

/// Decodes a PLY file whose first element is `vertex` with scalar properties including
/// x, y, z (and optionally red, green, blue; grey 128 when absent).
pub fn decode(bytes: &[u8]) -> Result<PointCloud> {
    let (header, rows) = decode_rows(bytes)?;
    let find = |name: &str| header.properties.iter().position(|(n, _)| n == name);
    let (Some(ix), Some(iy), Some(iz)) = (find("x"), find("y"), find("z")) else {
        return Err(Error::format("PLY", "vertex element lacks x, y or z"));
    };
    let rgb = [find("red"), find("green"), find("blue")];
    let mut cloud = PointCloud::default();
    for row in rows {
        cloud
            .positions
            .push([row[ix] as f32, row[iy] as f32, row[iz] as f32]);
        let channel = |i: Option<usize>| i.map_or(128, |i| row[i].clamp(0.0, 255.0) as u8);
        cloud
            .colours
            .push([channel(rgb[0]), channel(rgb[1]), channel(rgb[2])]);
    }
    Ok(cloud)
}

/// The per-vertex `confidence` property of a PLY file, in vertex order, or `None` when the
/// vertex element has none.
pub fn decode_confidence(bytes: &[u8]) -> Result<Option<Vec<f32>>> {
    let (header, rows) = decode_rows(bytes)?;
    let Some(i) = header
        .properties
        .iter()
        .position(|(n, _)| n == "confidence")
    else {
        return Ok(None);
    };
    Ok(Some(rows.iter().map(|row| row[i] as f32).collect()))
}

/// The header and the vertex rows (every scalar property, as f64) of a PLY file.
fn decode_rows(bytes: &[u8]) -> Result<(Header, Vec<Vec<f64>>)> {
    let header = parse_header(bytes)?;
    let body = &bytes[header.body_start..];
    let rows = match header.encoding {
        Encoding::Ascii => ascii_rows(body, header.vertices, header.properties.len())?,
        Encoding::BinaryLittleEndian => binary_rows(body, &header)?,
    };
    Ok((header, rows))
}

fn parse_header(bytes: &[u8]) -> Result<Header> {
    let bad = |reason: &str| Error::format("PLY", reason.to_string());
    let end_marker = b"end_header";
    let end = bytes
        .windows(end_marker.len())
        .position(|w| w == end_marker)
        .ok_or_else(|| bad("no end_header"))?;
    let mut body_start = end + end_marker.len();
    if bytes.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if bytes.get(body_start) != Some(&b'\n') {
        return Err(bad("end_header must end its line"));
    }
    let text = std::str::from_utf8(&bytes[..end]).map_err(|_| bad("header is not text"))?;
    let mut lines = text.lines().map(str::trim);
    if lines.next() != Some("ply") {
        return Err(bad("missing ply magic"));
    }
    let mut encoding = None;
    let mut vertices = None;
    let mut properties = Vec::new();
    let mut in_vertex = false;
    for line in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", "ascii", _] => encoding = Some(Encoding::Ascii),
            ["format", "binary_little_endian", _] => encoding = Some(Encoding::BinaryLittleEndian),
            ["format", other, _] => return Err(bad(&format!("unsupported format {other}"))),
            ["element", "vertex", n] if vertices.is_none() => {
                vertices = Some(
                    n.parse::<usize>()
                        .map_err(|_| bad("invalid vertex count"))?,
                );
                in_vertex = true;
            }
            ["element", ..] => {
                if vertices.is_none() {
                    return Err(bad("the vertex element must come first"));
                }
                in_vertex = false;
            }
            ["property", "list", ..] if in_vertex => {
                return Err(bad("list properties on vertices are not supported"));
            }
            ["property", ty, name] if in_vertex => {
                let scalar = Scalar::parse(ty).ok_or_else(|| bad(&format!("unknown type {ty}")))?;
                properties.push((name.to_string(), scalar));
            }
            _ => {}
        }
    }
    Ok(Header {
        encoding: encoding.ok_or_else(|| bad("missing format line"))?,
        vertices: vertices.ok_or_else(|| bad("no vertex element"))?,
        properties,
        body_start: body_start + 1,
    })
}

fn ascii_rows(body: &[u8], count: usize, width: usize) -> Result<Vec<Vec<f64>>> {
    let text =
        std::str::from_utf8(body).map_err(|_| Error::format("PLY", "ASCII body is not text"))?;
    let mut values = text.split_ascii_whitespace();
    (0..count)
        .map(|i| {
            (0..width)
                .map(|_| {
                    values
                        .next()
                        .and_then(|v| v.parse::<f64>().ok())
                        .ok_or_else(|| {
                            Error::format("PLY", format!("vertex {i} is missing or malformed"))
                        })
                })
                .collect()
        })
        .collect()
}

fn binary_rows(body: &[u8], header: &Header) -> Result<Vec<Vec<f64>>> {
    let stride: usize = header.properties.iter().map(|(_, s)| s.size()).sum();
    let need = stride.checked_mul(header.vertices);
    if need.is_none_or(|n| body.len() < n) {
        return Err(Error::format(
            "PLY",
            format!(
                "{} vertices need {} bytes, body has {}",
                header.vertices,
                stride * header.vertices,
                body.len()
            ),
        ));
    }
    Ok(body
        .chunks_exact(stride)
        .take(header.vertices)
        .map(|chunk| {
            let mut offset = 0;
            header
                .properties
                .iter()
                .map(|(_, s)| {
                    let v = s.read_le(&chunk[offset..]);
                    offset += s.size();
                    v
                })
                .collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud() -> PointCloud {
        PointCloud {
            positions: vec![[0.0, -1.5, 2.25], [1e-3, 4.0, 8.0], [f32::NAN, 0.0, 1.0]],
            colours: vec![[255, 0, 7], [1, 2, 3], [9, 9, 9]],
        }
    }

    #[test]
    fn confidence_round_trips_and_follows_the_kept_points() {
        for encoding in [Encoding::BinaryLittleEndian, Encoding::Ascii] {
            let bytes =
                encode_with_confidence(&cloud(), Some(&[0.25, 1.0, 0.5]), encoding).unwrap();
            assert_eq!(decode(&bytes).unwrap().positions, cloud().positions[..2]);
            assert_eq!(decode_confidence(&bytes).unwrap(), Some(vec![0.25, 1.0]));
            let plain = encode(&cloud(), encoding).unwrap();
            assert_eq!(decode_confidence(&plain).unwrap(), None);
        }
        assert!(encode_with_confidence(&cloud(), Some(&[0.5]), Encoding::Ascii).is_err());
    }

    #[test]
    fn binary_and_ascii_round_trip_skipping_non_finite_points() {
        for encoding in [Encoding::BinaryLittleEndian, Encoding::Ascii] {
            let bytes = encode(&cloud(), encoding).unwrap();
            let text = String::from_utf8_lossy(&bytes[..120]).to_string();
            assert!(text.contains("element vertex 2"), "{text}");
            let back = decode(&bytes).unwrap();
            assert_eq!(back.positions, cloud().positions[..2]);
            assert_eq!(back.colours, cloud().colours[..2]);
        }
    }

    #[test]
    fn foreign_property_order_and_extra_elements_are_read() {
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty uchar blue\nproperty double z\n\
                    property float nx\nproperty float x\nproperty float y\nelement face 0\n\
                    property list uchar int vertex_indices\nend_header\n5 3.5 0 1 2\n";
        let c = decode(text.as_bytes()).unwrap();
        assert_eq!(c.positions, vec![[1.0, 2.0, 3.5]]);
        assert_eq!(c.colours, vec![[128, 128, 5]]);
    }

    #[test]
    fn malformed_files_are_errors() {
        assert!(decode(b"").is_err());
        assert!(
            decode(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\n")
                .is_err()
        );
        let mut truncated = encode(&cloud(), Encoding::BinaryLittleEndian).unwrap();
        truncated.truncate(truncated.len() - 3);
        assert!(decode(&truncated).is_err());
        let mismatched = PointCloud {
            positions: vec![[0.0; 3]],
            colours: vec![],
        };
        assert!(encode(&mismatched, Encoding::Ascii).is_err());
    }
}
