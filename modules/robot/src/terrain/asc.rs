//! ESRI ASCII grid (`.asc`) terrain files.
//!
//! The format is a header of `key value` lines followed by the rows of samples:
//!
//! ```text
//! ncols        4            number of columns (along world X)
//! nrows        3            number of rows (along world Y)
//! xllcorner    0.0          X of the lower-left corner of the lower-left cell, or
//!                           xllcenter: X of the centre of the lower-left cell
//! yllcorner    0.0          Y likewise (yllcorner or yllcenter)
//! cellsize     0.5          side of a cell, metres, greater than zero
//! NODATA_value -9999        optional: the value that marks a missing sample
//! 0.1 0.2 0.3 0.4           row 0: the NORTHERNMOST row (largest Y)
//! ...                       one row per line, nrows rows, ncols values each
//! ```
//!
//! Axis convention: world X grows along a row (east), world Y grows toward the top of the
//! file (north), so file row 0 is the largest Y and the last row the smallest; each value is
//! the height (world Z, metres) at the centre of its cell. Header keys are case-insensitive.
//! A malformed file is refused with the line number and the reason.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Point2;

use super::{HeightField, TerrainError};
use crate::grid::{CellIndex, Grid};

/// Largest grid accepted (cells), to refuse absurd headers before allocating.
const MAX_CELLS: usize = 200_000_000;

/// Why an `.asc` file was refused.
#[derive(Debug, thiserror::Error)]
pub enum AscError {
    /// The file could not be read or written.
    #[error("cannot access {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The text is malformed.
    #[error("line {line}: {reason}")]
    Syntax {
        /// 1-based line number.
        line: usize,
        /// What is wrong and what was expected.
        reason: String,
    },
    /// A sample is NODATA and the caller asked to refuse holes.
    #[error(
        "sample at file row {row}, column {col} is NODATA; fill holes with NoData::FillWith or \
         NoData::FillLowest, or fix the file"
    )]
    NoData {
        /// 0-based file row (0 = northernmost).
        row: usize,
        /// 0-based column.
        col: usize,
    },
    /// Every sample is NODATA.
    #[error("every sample is NODATA; the file has no terrain")]
    AllNoData,
    /// The samples do not make a usable height field.
    #[error(transparent)]
    Terrain(#[from] TerrainError),
}

/// What to do with NODATA samples when making a height field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NoData {
    /// Refuse the file if any sample is NODATA.
    Refuse,
    /// Use this height (metres) for NODATA samples.
    FillWith(f64),
    /// Use the lowest valid height in the file.
    FillLowest,
}

/// The contents of an `.asc` file: samples (`None` = NODATA) on a [`Grid`] whose cell (0, 0)
/// is the south-west (lower-left) sample.
#[derive(Debug, Clone, PartialEq)]
pub struct AscGrid {
    /// The samples; the grid origin is the centre of the lower-left cell.
    pub grid: Grid<Option<f64>>,
    /// The NODATA marker written by [`to_asc_string`](Self::to_asc_string), if any.
    pub nodata_value: Option<f64>,
}

#[derive(Default)]
struct Header {
    ncols: Option<usize>,
    nrows: Option<usize>,
    xll: Option<(f64, bool)>,
    yll: Option<(f64, bool)>,
    cellsize: Option<f64>,
    nodata: Option<f64>,
}

fn syntax(line: usize, reason: impl Into<String>) -> AscError {
    AscError::Syntax {
        line,
        reason: reason.into(),
    }
}

impl AscGrid {
    /// Parses the text of an `.asc` file.
    pub fn parse(text: &str) -> Result<Self, AscError> {
        let mut header = Header::default();
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l)).peekable();
        // Header: lines until the first line that starts with a number.
        while let Some(&(n, line)) = lines.peek() {
            let mut tokens = line.split_whitespace();
            let Some(key) = tokens.next() else {
                lines.next();
                continue;
            };
            if key.parse::<f64>().is_ok() {
                break;
            }
            lines.next();
            let value = tokens
                .next()
                .ok_or_else(|| syntax(n, format!("header key `{key}` has no value")))?;
            if let Some(extra) = tokens.next() {
                return Err(syntax(
                    n,
                    format!("unexpected `{extra}` after the value of `{key}`"),
                ));
            }
            let number = || -> Result<f64, AscError> {
                value
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| syntax(n, format!("value `{value}` of `{key}` is not a number")))
            };
            let count = || -> Result<usize, AscError> {
                value
                    .parse::<usize>()
                    .ok()
                    .filter(|&v| v > 0)
                    .ok_or_else(|| {
                        syntax(
                            n,
                            format!("`{key}` must be a whole number above zero, got `{value}`"),
                        )
                    })
            };
            let lower = key.to_ascii_lowercase();
            let duplicate = || syntax(n, format!("header key `{key}` is given twice"));
            match lower.as_str() {
                "ncols" => set_once(&mut header.ncols, count()?).ok_or_else(duplicate)?,
                "nrows" => set_once(&mut header.nrows, count()?).ok_or_else(duplicate)?,
                "xllcorner" | "xllcenter" => {
                    set_once(&mut header.xll, (number()?, lower == "xllcenter"))
                        .ok_or_else(|| syntax(n, "give either xllcorner or xllcenter, once"))?
                }
                "yllcorner" | "yllcenter" => {
                    set_once(&mut header.yll, (number()?, lower == "yllcenter"))
                        .ok_or_else(|| syntax(n, "give either yllcorner or yllcenter, once"))?
                }
                "cellsize" => {
                    let v = number()?;
                    if v <= 0.0 {
                        return Err(syntax(
                            n,
                            format!("cellsize must be greater than zero, got {v}"),
                        ));
                    }
                    set_once(&mut header.cellsize, v).ok_or_else(duplicate)?
                }
                "nodata_value" => set_once(&mut header.nodata, number()?).ok_or_else(duplicate)?,
                _ => {
                    return Err(syntax(
                        n,
                        format!(
                            "unknown header key `{key}`; expected ncols, nrows, xllcorner/xllcenter, \
                             yllcorner/yllcenter, cellsize or NODATA_value"
                        ),
                    ));
                }
            }
        }
        let first_data_line = lines.peek().map_or(text.lines().count() + 1, |&(n, _)| n);
        let missing = |key: &str| {
            syntax(
                first_data_line,
                format!("missing header key `{key}` before the data"),
            )
        };
        let ncols = header.ncols.ok_or_else(|| missing("ncols"))?;
        let nrows = header.nrows.ok_or_else(|| missing("nrows"))?;
        let (xll, x_centre) = header
            .xll
            .ok_or_else(|| missing("xllcorner or xllcenter"))?;
        let (yll, y_centre) = header
            .yll
            .ok_or_else(|| missing("yllcorner or yllcenter"))?;
        let cellsize = header.cellsize.ok_or_else(|| missing("cellsize"))?;
        if ncols.checked_mul(nrows).is_none_or(|c| c > MAX_CELLS) {
            return Err(syntax(
                first_data_line,
                format!("grid of {ncols} x {nrows} cells is too large"),
            ));
        }
        let origin = Point2::new(
            if x_centre { xll } else { xll + 0.5 * cellsize },
            if y_centre { yll } else { yll + 0.5 * cellsize },
        );

        let mut cells = vec![None; ncols * nrows];
        let mut row = 0usize;
        let mut last_line = first_data_line.saturating_sub(1);
        for (n, line) in lines {
            last_line = n;
            if line.trim().is_empty() {
                continue;
            }
            if row == nrows {
                return Err(syntax(n, format!("more rows than nrows = {nrows}")));
            }
            let iy = nrows - 1 - row;
            let mut col = 0usize;
            for token in line.split_whitespace() {
                if col == ncols {
                    let extra = line.split_whitespace().count();
                    return Err(syntax(
                        n,
                        format!("row {row} has {extra} values, expected ncols = {ncols}"),
                    ));
                }
                let v: f64 = token.parse().map_err(|_| {
                    syntax(
                        n,
                        format!("value `{token}` in column {col} is not a number"),
                    )
                })?;
                let sample = if header.nodata == Some(v) {
                    None
                } else if v.is_finite() {
                    Some(v)
                } else {
                    return Err(syntax(
                        n,
                        format!("value `{token}` in column {col} is not a finite number"),
                    ));
                };
                cells[iy * ncols + col] = sample;
                col += 1;
            }
            if col != ncols {
                return Err(syntax(
                    n,
                    format!("row {row} has {col} values, expected ncols = {ncols}"),
                ));
            }
            row += 1;
        }
        if row < nrows {
            return Err(syntax(
                last_line + 1,
                format!("file ends after {row} of nrows = {nrows} rows"),
            ));
        }
        let grid = Grid::from_vec(origin, cellsize, ncols, nrows, cells)
            .map_err(|e| syntax(first_data_line, e.to_string()))?;
        Ok(Self {
            grid,
            nodata_value: header.nodata,
        })
    }

    /// Reads and parses an `.asc` file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, AscError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| AscError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&text)
    }

    /// The samples of a height field (none missing).
    pub fn from_height_field(terrain: &HeightField) -> Self {
        Self {
            grid: terrain.grid().map(|&h| Some(h)),
            nodata_value: None,
        }
    }

    /// A height field from the samples, treating NODATA as `policy` says.
    pub fn to_height_field(&self, policy: NoData) -> Result<HeightField, AscError> {
        let lowest = self.grid.cells().iter().flatten().copied().reduce(f64::min);
        let fill = match policy {
            NoData::Refuse => {
                if let Some((c, _)) = self.grid.iter().find(|(_, v)| v.is_none()) {
                    return Err(AscError::NoData {
                        row: self.grid.ny() - 1 - c.iy,
                        col: c.ix,
                    });
                }
                0.0
            }
            NoData::FillWith(h) => h,
            NoData::FillLowest => lowest.ok_or(AscError::AllNoData)?,
        };
        Ok(HeightField::from_grid(
            self.grid.map(|v| v.unwrap_or(fill)),
        )?)
    }

    /// The file text: `xllcorner`/`yllcorner` header, rows north to south. Numbers are
    /// written in Rust's shortest round-trip form, so parsing the text gives back the
    /// same samples exactly.
    pub fn to_asc_string(&self) -> String {
        let g = &self.grid;
        let r = g.resolution_m();
        let mut s = String::new();
        let _ = writeln!(s, "ncols {}", g.nx());
        let _ = writeln!(s, "nrows {}", g.ny());
        let _ = writeln!(s, "xllcenter {}", g.origin().x);
        let _ = writeln!(s, "yllcenter {}", g.origin().y);
        let _ = writeln!(s, "cellsize {r}");
        let nodata = self.nodata_value.unwrap_or(-9999.0);
        let has_holes = g.cells().iter().any(Option::is_none);
        if self.nodata_value.is_some() || has_holes {
            let _ = writeln!(s, "NODATA_value {nodata}");
        }
        for iy in (0..g.ny()).rev() {
            for ix in 0..g.nx() {
                if ix > 0 {
                    s.push(' ');
                }
                let v = g
                    .get(CellIndex::new(ix, iy))
                    .copied()
                    .flatten()
                    .unwrap_or(nodata);
                let _ = write!(s, "{v}");
            }
            s.push('\n');
        }
        s
    }

    /// Writes the file.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), AscError> {
        let path = path.as_ref();
        std::fs::write(path, self.to_asc_string()).map_err(|source| AscError::Io {
            path: path.display().to_string(),
            source,
        })
    }
}

fn set_once<T>(slot: &mut Option<T>, value: T) -> Option<()> {
    if slot.is_some() {
        return None;
    }
    *slot = Some(value);
    Some(())
}

/// Reads an `.asc` file as a height field.
pub fn read_height_field(path: impl AsRef<Path>, policy: NoData) -> Result<HeightField, AscError> {
    AscGrid::read(path)?.to_height_field(policy)
}

/// Writes a height field as an `.asc` file.
pub fn write_height_field(path: impl AsRef<Path>, terrain: &HeightField) -> Result<(), AscError> {
    AscGrid::from_height_field(terrain).write(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "ncols 3\nnrows 2\nxllcorner 1.0\nyllcorner 2.0\ncellsize 0.5\nNODATA_value -9999\n\
                         1 2 3\n4 -9999 6\n";

    fn err_of(text: &str) -> (usize, String) {
        match AscGrid::parse(text) {
            Err(AscError::Syntax { line, reason }) => (line, reason),
            other => panic!("expected a syntax error, got {other:?}"),
        }
    }

    #[test]
    fn rows_run_north_to_south() {
        let a = AscGrid::parse(SMALL).unwrap();
        assert_eq!(a.grid.origin(), Point2::new(1.25, 2.25));
        // The last file row is the southernmost (iy = 0).
        assert_eq!(a.grid.get(CellIndex::new(0, 0)), Some(&Some(4.0)));
        assert_eq!(a.grid.get(CellIndex::new(1, 0)), Some(&None));
        assert_eq!(a.grid.get(CellIndex::new(2, 1)), Some(&Some(3.0)));
        let t = a.to_height_field(NoData::FillLowest).unwrap();
        assert_eq!(t.height_at(1.75, 2.25), 1.0);
        assert!(matches!(
            a.to_height_field(NoData::Refuse),
            Err(AscError::NoData { row: 1, col: 1 })
        ));
        assert_eq!(
            a.to_height_field(NoData::FillWith(-1.0))
                .unwrap()
                .height_at(1.75, 2.25),
            -1.0
        );
    }

    #[test]
    fn centre_registration_and_case_insensitive_keys() {
        let text = "NCOLS 2\nNROWS 2\nXLLCENTER 0\nYLLCENTER 0\nCELLSIZE 1\n0 1\n2 3\n";
        let a = AscGrid::parse(text).unwrap();
        assert_eq!(a.grid.origin(), Point2::new(0.0, 0.0));
        assert_eq!(a.nodata_value, None);
    }

    #[test]
    fn round_trips_exactly() {
        let a = AscGrid::parse(SMALL).unwrap();
        let again = AscGrid::parse(&a.to_asc_string()).unwrap();
        assert_eq!(a, again);
        let t = HeightField::new(
            Point2::new(0.01, -3.0),
            0.02,
            4,
            3,
            (0..12).map(|i| i as f64 * 0.1234567).collect(),
        )
        .unwrap();
        let back = AscGrid::parse(&AscGrid::from_height_field(&t).to_asc_string())
            .unwrap()
            .to_height_field(NoData::Refuse)
            .unwrap();
        assert_eq!(t, back);
    }

    #[test]
    fn malformed_files_name_line_and_reason() {
        let (line, reason) = err_of("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2 3\n4 5 6\n");
        assert_eq!(line, 5);
        assert!(reason.contains("cellsize"), "{reason}");

        let (line, reason) =
            err_of("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize -1\n1 2 3\n");
        assert_eq!(line, 5);
        assert!(reason.contains("greater than zero"), "{reason}");

        let (line, reason) = err_of("ncols 3\nnrows 2\nxllcorner 0\nyllcorner zero\ncellsize 1\n");
        assert_eq!(line, 4);
        assert!(reason.contains("not a number"), "{reason}");

        let (line, reason) =
            err_of("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5\n");
        assert_eq!(line, 7);
        assert!(reason.contains("2 values, expected ncols = 3"), "{reason}");

        let (line, reason) =
            err_of("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3 4\n4 5 6\n");
        assert_eq!(line, 6);
        assert!(reason.contains("expected ncols = 3"), "{reason}");

        let (line, reason) =
            err_of("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n");
        assert_eq!(line, 7);
        assert!(reason.contains("1 of nrows = 2"), "{reason}");

        let (line, reason) =
            err_of("ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n");
        assert_eq!(line, 7);
        assert!(reason.contains("more rows"), "{reason}");

        let (line, reason) =
            err_of("ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 x 3\n");
        assert_eq!(line, 6);
        assert!(reason.contains("`x` in column 1"), "{reason}");

        let (line, reason) = err_of("ncols 3\nnrows 1\nxllcorner 0\nxllcenter 0\n");
        assert_eq!(line, 4);
        assert!(reason.contains("either"), "{reason}");

        let (line, reason) = err_of("ncols 0\n");
        assert_eq!(line, 1);
        assert!(reason.contains("above zero"), "{reason}");

        let (line, reason) = err_of("ncols 2\ncolour red\n");
        assert_eq!(line, 2);
        assert!(reason.contains("unknown header key `colour`"), "{reason}");
    }

    #[test]
    fn files_load_and_write() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.asc");
        std::fs::write(&path, SMALL).unwrap();
        let t = read_height_field(&path, NoData::FillWith(0.0)).unwrap();
        let out = dir.path().join("out.asc");
        write_height_field(&out, &t).unwrap();
        assert_eq!(read_height_field(&out, NoData::Refuse).unwrap(), t);
        let err = read_height_field(dir.path().join("missing.asc"), NoData::Refuse).unwrap_err();
        assert!(err.to_string().contains("missing.asc"));
    }
}
