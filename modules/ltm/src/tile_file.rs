//! The on-disk format of map tiles paged out by the scroller.
//!
//! # Format (`tile_<tx>_<ty>.ltmtile`, version 1), little-endian
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `TCALTMT1` |
//! | 4 | `u32` cells per tile side `T` |
//! | 8 | `f64` resolution, metres |
//! | 8 + 8 | `i64` tile indices `tx`, `ty` (the tile holds lattice cells `tx*T ..` by `ty*T ..`) |
//! | `9 T^2` | cells, row-major: `u8` state (0 unknown, 1 occluded, 2 known), `f32` elevation, `f32` sigma |
//!
//! A tile is read back only if its side, resolution and indices are the ones expected.

use std::path::{Path, PathBuf};

use crate::cell::{Cell, CellState};
use crate::error::{LtmError, Result};

/// Magic bytes of a tile file.
pub const MAGIC: &[u8; 8] = b"TCALTMT1";
/// Extension of tile files.
pub const EXTENSION: &str = "ltmtile";
const HEADER: usize = 8 + 4 + 8 + 16;
const CELL: usize = 9;

/// The file name of tile `(tx, ty)` in `dir`.
pub fn tile_path(dir: &Path, tx: i64, ty: i64) -> PathBuf {
    dir.join(format!("tile_{tx}_{ty}.{EXTENSION}"))
}

/// The tile indices a file name encodes, if it is a tile file's name.
pub fn parse_tile_name(name: &str) -> Option<(i64, i64)> {
    let stem = name
        .strip_prefix("tile_")?
        .strip_suffix(&format!(".{EXTENSION}"))?;
    let (a, b) = stem.split_once('_')?;
    Some((a.parse().ok()?, b.parse().ok()?))
}

/// Encodes a tile.
pub fn encode(side: usize, resolution_m: f64, tx: i64, ty: i64, cells: &[Cell]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER + CELL * cells.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(side as u32).to_le_bytes());
    out.extend_from_slice(&resolution_m.to_le_bytes());
    out.extend_from_slice(&tx.to_le_bytes());
    out.extend_from_slice(&ty.to_le_bytes());
    for c in cells {
        out.push(c.state as u8);
        out.extend_from_slice(&c.elevation_m.to_le_bytes());
        out.extend_from_slice(&c.sigma_m.to_le_bytes());
    }
    out
}

/// Decodes a tile, checking it is the one expected.
pub fn decode(
    bytes: &[u8],
    path: &Path,
    side: usize,
    resolution_m: f64,
    tx: i64,
    ty: i64,
) -> Result<Vec<Cell>> {
    let bad = |reason: String| LtmError::TileFile {
        path: path.to_owned(),
        reason,
    };
    let expected_len = HEADER + CELL * side * side;
    if bytes.len() != expected_len {
        return Err(bad(format!(
            "it has {} bytes, a {side} x {side} tile has {expected_len}",
            bytes.len()
        )));
    }
    let (head, body) = bytes.split_at(HEADER);
    if &head[..8] != MAGIC {
        return Err(bad("it does not start with TCALTMT1".into()));
    }
    let word = |at: usize| -> [u8; 8] {
        let mut w = [0; 8];
        w.copy_from_slice(&head[at..at + 8]);
        w
    };
    let file_side = u32::from_le_bytes([head[8], head[9], head[10], head[11]]) as usize;
    let file_res = f64::from_le_bytes(word(12));
    let (ftx, fty) = (i64::from_le_bytes(word(20)), i64::from_le_bytes(word(28)));
    if file_side != side || file_res != resolution_m || (ftx, fty) != (tx, ty) {
        return Err(bad(format!(
            "it holds tile ({ftx}, {fty}) of side {file_side} at {file_res} m, not tile ({tx}, \
             {ty}) of side {side} at {resolution_m} m"
        )));
    }
    body.chunks_exact(CELL)
        .enumerate()
        .map(|(k, c)| {
            let state = CellState::from_u8(c[0])
                .ok_or_else(|| bad(format!("cell {k} has state byte {}", c[0])))?;
            Ok(Cell {
                state,
                elevation_m: f32::from_le_bytes([c[1], c[2], c[3], c[4]]),
                sigma_m: f32::from_le_bytes([c[5], c[6], c[7], c[8]]),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_round_trip_bit_for_bit() {
        let cells = vec![
            Cell::known(1.25, 0.01),
            Cell::occluded(-0.5),
            Cell::UNKNOWN,
            Cell::known(f32::MIN_POSITIVE, 3.0),
        ];
        let bytes = encode(2, 0.05, -3, 7, &cells);
        let p = Path::new("t");
        assert_eq!(decode(&bytes, p, 2, 0.05, -3, 7).unwrap(), cells);
        assert!(decode(&bytes, p, 2, 0.1, -3, 7).is_err());
        assert!(decode(&bytes, p, 2, 0.05, -3, 8).is_err());
        assert!(decode(&bytes[1..], p, 2, 0.05, -3, 7).is_err());
        let mut corrupt = bytes.clone();
        corrupt[HEADER] = 9;
        assert!(
            decode(&corrupt, p, 2, 0.05, -3, 7)
                .unwrap_err()
                .to_string()
                .contains("state byte")
        );
    }

    #[test]
    fn names_round_trip() {
        let p = tile_path(Path::new("/x"), -12, 4);
        let name = p.file_name().unwrap().to_str().unwrap();
        assert_eq!(parse_tile_name(name), Some((-12, 4)));
        assert_eq!(parse_tile_name("tile_1.ltmtile"), None);
        assert_eq!(parse_tile_name("other"), None);
    }
}
