//! The second virtual sensor: image sequences stored on disk (§5.2.1 found replaying stored
//! images useful for development), and the file format they are stored in.
//!
//! # File format (`.tcarange`, version 1)
//!
//! One image per file, little-endian:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `TCARIMG1` |
//! | 4 | `u32` length `H` of the header |
//! | `H` | header: UTF-8 JSON object with `sensor` (`"Erim"` or `"Perceptron"`), `width`, `height`, `range_resolution_m`, `ambiguity_m`, `azimuth_fov_rad`, `elevation_fov_rad`, `sequence`, and the transforms `locus_from_scanner`, `scanner_from_body`, `body_from_global` as `{"m": [16 numbers, row-major]}` |
//! | `2 w h` | range counts, `u16` each, row-major (row 0 at the top) |
//! | `2 w h` | reflectance counts, `u16` each, row-major |
//!
//! Nothing may follow. A sequence is a directory of such files, played in the lexicographic
//! order of their names ([`write_sequence_image`] names them `image-000000.tcarange`, ...).
//! Every image is checked against its sensor when read.

use std::fs;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tca_robot::CarriagePose;
use tca_single_leg_messages::{RangeImage, SensorKind, Transform};

use crate::error::{IsmError, Result};
use crate::sensor::RangeSensor;
use crate::spec::SensorSpec;

/// The magic bytes opening a stored image.
pub const MAGIC: &[u8; 8] = b"TCARIMG1";
/// The extension of stored images.
pub const EXTENSION: &str = "tcarange";
/// Largest header accepted, bytes.
const MAX_HEADER: usize = 64 * 1024;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Header {
    sensor: SensorKind,
    width: u32,
    height: u32,
    range_resolution_m: f64,
    ambiguity_m: f64,
    azimuth_fov_rad: f64,
    elevation_fov_rad: f64,
    sequence: u64,
    locus_from_scanner: Transform,
    scanner_from_body: Transform,
    body_from_global: Transform,
}

/// Encodes an image in the stored format.
pub fn encode_image(image: &RangeImage) -> Vec<u8> {
    let header = Header {
        sensor: image.sensor,
        width: image.width,
        height: image.height,
        range_resolution_m: image.range_resolution_m,
        ambiguity_m: image.ambiguity_m,
        azimuth_fov_rad: image.azimuth_fov_rad,
        elevation_fov_rad: image.elevation_fov_rad,
        sequence: image.sequence,
        locus_from_scanner: image.locus_from_scanner,
        scanner_from_body: image.scanner_from_body,
        body_from_global: image.body_from_global,
    };
    // Serialising plain numbers and strings into JSON cannot fail.
    let json = serde_json::to_vec(&header).unwrap_or_default();
    let mut out = Vec::with_capacity(
        12 + json.len() + 2 * (image.range_counts.len() + image.reflectance.len()),
    );
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    for v in image.range_counts.iter().chain(&image.reflectance) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Decodes a stored image and checks it against its sensor. `path` only names the source in
/// errors.
pub fn decode_image(bytes: &[u8], path: &Path) -> Result<RangeImage> {
    let bad = |reason: String| IsmError::ImageFile {
        path: path.to_owned(),
        reason,
    };
    let rest = bytes
        .strip_prefix(MAGIC.as_slice())
        .ok_or_else(|| bad("it does not start with TCARIMG1: not a stored range image".into()))?;
    let (len, rest) = rest
        .split_first_chunk::<4>()
        .ok_or_else(|| bad("it ends inside the header length".into()))?;
    let len = u32::from_le_bytes(*len) as usize;
    if len > MAX_HEADER || len > rest.len() {
        return Err(bad(format!(
            "its header length {len} is beyond the file ({} bytes left) or the {MAX_HEADER}-byte limit",
            rest.len()
        )));
    }
    let (json, pixels) = rest.split_at(len);
    let header: Header =
        serde_json::from_slice(json).map_err(|e| bad(format!("its header is not valid: {e}")))?;
    let n = (header.width as usize)
        .checked_mul(header.height as usize)
        .ok_or_else(|| bad("its size overflows".into()))?;
    if Some(pixels.len()) != n.checked_mul(4) {
        return Err(bad(format!(
            "a {} x {} image needs {} bytes of pixels but the file has {}",
            header.width,
            header.height,
            n.saturating_mul(4),
            pixels.len()
        )));
    }
    let words: Vec<u16> = pixels
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    let (range, refl) = words.split_at(n);
    let image = RangeImage {
        sensor: header.sensor,
        width: header.width,
        height: header.height,
        range_counts: range.to_vec(),
        reflectance: refl.to_vec(),
        range_resolution_m: header.range_resolution_m,
        ambiguity_m: header.ambiguity_m,
        azimuth_fov_rad: header.azimuth_fov_rad,
        elevation_fov_rad: header.elevation_fov_rad,
        locus_from_scanner: header.locus_from_scanner,
        scanner_from_body: header.scanner_from_body,
        body_from_global: header.body_from_global,
        sequence: header.sequence,
    };
    SensorSpec::of(image.sensor).check_image(&image)?;
    Ok(image)
}

/// Writes one image to a file.
pub fn write_image(path: impl AsRef<Path>, image: &RangeImage) -> Result<()> {
    let path = path.as_ref();
    fs::write(path, encode_image(image)).map_err(|source| IsmError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Reads and checks one image file.
pub fn read_image(path: impl AsRef<Path>) -> Result<RangeImage> {
    let path = path.as_ref();
    let bytes = fs::read(path).map_err(|source| IsmError::Io {
        path: path.to_owned(),
        source,
    })?;
    decode_image(&bytes, path)
}

/// Appends an image to a sequence directory (created if needed) as
/// `image-<index, 6 digits>.tcarange`, `index` being the number of images already there.
/// Returns the file written.
pub fn write_sequence_image(dir: impl AsRef<Path>, image: &RangeImage) -> Result<PathBuf> {
    let dir = dir.as_ref();
    fs::create_dir_all(dir).map_err(|source| IsmError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let index = list_images(dir)?.len();
    let path = dir.join(format!("image-{index:06}.{EXTENSION}"));
    write_image(&path, image)?;
    Ok(path)
}

fn list_images(dir: &Path) -> Result<Vec<PathBuf>> {
    let io = |source| IsmError::Io {
        path: dir.to_owned(),
        source,
    };
    let mut files = Vec::new();
    for entry in fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if path.extension().is_some_and(|e| e == EXTENSION) && path.is_file() {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// A virtual sensor replaying a stored sequence of one sensor's images.
#[derive(Debug, Clone)]
pub struct StoredSequence {
    dir: PathBuf,
    spec: SensorSpec,
    files: Vec<PathBuf>,
    next: usize,
    looping: bool,
}

impl StoredSequence {
    /// Opens the sequence in `dir` of `sensor` images. With `looping`, the sequence starts
    /// again after its last image; without, acquiring past the end is an error.
    pub fn open(dir: impl AsRef<Path>, sensor: SensorKind, looping: bool) -> Result<Self> {
        let dir = dir.as_ref().to_owned();
        let files = list_images(&dir)?;
        if files.is_empty() {
            return Err(IsmError::Sequence {
                dir,
                reason: format!("it holds no .{EXTENSION} images"),
            });
        }
        Ok(Self {
            dir,
            spec: SensorSpec::of(sensor),
            files,
            next: 0,
            looping,
        })
    }

    /// Images in the sequence.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// Whether the sequence is empty (never, once opened).
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }
}

impl RangeSensor for StoredSequence {
    fn spec(&self) -> &SensorSpec {
        &self.spec
    }

    fn acquire_from_body(
        &mut self,
        _world_from_body: &nalgebra::Isometry3<f64>,
    ) -> Result<RangeImage> {
        self.acquire(&CarriagePose::level(0.0))
    }

    fn acquire(&mut self, _pose: &CarriagePose) -> Result<RangeImage> {
        if self.next >= self.files.len() {
            if !self.looping {
                return Err(IsmError::Sequence {
                    dir: self.dir.clone(),
                    reason: format!(
                        "all {} images have been played; open it with looping to replay",
                        self.files.len()
                    ),
                });
            }
            self.next = 0;
        }
        let path = &self.files[self.next];
        let image = read_image(path)?;
        if image.sensor != self.spec.kind {
            return Err(IsmError::ImageFile {
                path: path.clone(),
                reason: format!(
                    "it is a {:?} image in a {:?} sequence",
                    image.sensor, self.spec.kind
                ),
            });
        }
        self.next += 1;
        Ok(image)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use nalgebra::Point2;
    use tca_robot::{HeightField, LegParams};

    use crate::VirtualScanner;

    fn image(seq: u64) -> RangeImage {
        let terrain = Arc::new(
            HeightField::flat(Point2::new(-5.0, -5.0), Point2::new(12.0, 20.0), 0.5, 0.0).unwrap(),
        );
        VirtualScanner::new(SensorSpec::erim(), terrain, &LegParams::default())
            .cast(&CarriagePose::level(1.0), seq)
            .unwrap()
    }

    #[test]
    fn images_round_trip_through_a_sequence_directory() {
        let dir = tempfile::tempdir().unwrap();
        let a = image(0);
        let b = image(1);
        write_sequence_image(dir.path(), &a).unwrap();
        write_sequence_image(dir.path(), &b).unwrap();
        let mut seq = StoredSequence::open(dir.path(), SensorKind::Erim, false).unwrap();
        assert_eq!(seq.len(), 2);
        let pose = CarriagePose::level(7.0);
        assert_eq!(seq.acquire(&pose).unwrap(), a);
        assert_eq!(seq.acquire(&pose).unwrap(), b);
        let e = seq.acquire(&pose).unwrap_err().to_string();
        assert!(e.contains("have been played"), "{e}");
        let mut looping = StoredSequence::open(dir.path(), SensorKind::Erim, true).unwrap();
        for _ in 0..3 {
            looping.acquire(&pose).unwrap();
        }
    }

    #[test]
    fn corrupt_and_mismatched_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.tcarange");
        let mut bytes = encode_image(&image(0));
        bytes.truncate(bytes.len() - 1);
        std::fs::write(&path, &bytes).unwrap();
        let e = read_image(&path).unwrap_err().to_string();
        assert!(e.contains("needs"), "{e}");
        std::fs::write(&path, b"hello").unwrap();
        assert!(
            read_image(&path)
                .unwrap_err()
                .to_string()
                .contains("TCARIMG1")
        );
        // An Erim image claiming to be 64 x 64.
        let mut small = image(0);
        small.width = 64;
        small.range_counts.truncate(64 * 64);
        small.reflectance.truncate(64 * 64);
        write_image(&path, &small).unwrap();
        let e = read_image(&path).unwrap_err().to_string();
        assert!(e.contains("must be 256 x 64"), "{e}");
        // A Perceptron sequence refuses Erim images.
        let mut seq = StoredSequence::open(dir.path(), SensorKind::Perceptron, false).unwrap();
        write_image(&path, &image(0)).unwrap();
        let e = seq
            .acquire(&CarriagePose::level(1.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("Erim image in a Perceptron"), "{e}");
        let empty = tempfile::tempdir().unwrap();
        assert!(StoredSequence::open(empty.path(), SensorKind::Erim, true).is_err());
    }
}
