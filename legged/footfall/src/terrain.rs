//! The terrain as the collision checker sees it: the digital elevation model around one leg
//! turned into a triangle mesh (two triangles per grid cell, every sample kept), optionally
//! raised, with a pyramid of maxima that rules out most parts without a mesh query.

use nalgebra::Point2;
use parry3d_f64::math::Vector;
use parry3d_f64::shape::TriMesh;
use tca_robot::HeightField;

use crate::error::FootfallError;

/// A square of the terrain as a mesh.
#[derive(Clone)]
pub struct TerrainPatch {
    /// The mesh, world frame.
    pub(crate) mesh: TriMesh,
    /// The heights of the patch's samples (raised), row-major.
    heights: Vec<f64>,
    origin: Point2<f64>,
    resolution_m: f64,
    nx: usize,
    ny: usize,
    /// Maxima of 2^k x 2^k blocks of samples, k = 1, 2, ...
    levels: Vec<MaxLevel>,
    raise_m: f64,
}

impl std::fmt::Debug for TerrainPatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TerrainPatch")
            .field("origin", &self.origin)
            .field("nx", &self.nx)
            .field("ny", &self.ny)
            .field("triangles", &self.triangles())
            .field("raise_m", &self.raise_m)
            .finish()
    }
}

#[derive(Debug, Clone)]
struct MaxLevel {
    /// Block side in samples.
    block: usize,
    bx: usize,
    by: usize,
    max: Vec<f64>,
}

impl TerrainPatch {
    /// The samples of `terrain` within the square of half-side `half_m` about `centre`
    /// (clipped to the terrain), raised by `raise_m`.
    pub fn around(
        terrain: &HeightField,
        centre: Point2<f64>,
        half_m: f64,
        raise_m: f64,
    ) -> Result<TerrainPatch, FootfallError> {
        if !(half_m.is_finite() && half_m > 0.0 && raise_m.is_finite()) {
            return Err(FootfallError::Params(format!(
                "a terrain patch needs a positive size and a finite raise, got {half_m} and {raise_m}"
            )));
        }
        let g = terrain.grid();
        let Some((xs, ys)) = g.cell_range(
            Point2::new(centre.x - half_m, centre.y - half_m),
            Point2::new(centre.x + half_m, centre.y + half_m),
        ) else {
            return Err(FootfallError::Scene(format!(
                "the leg at ({:.2}, {:.2}) is off the terrain",
                centre.x, centre.y
            )));
        };
        let (x0, y0) = (*xs.start(), *ys.start());
        let (nx, ny) = (xs.end() - x0 + 1, ys.end() - y0 + 1);
        if nx < 2 || ny < 2 {
            return Err(FootfallError::Scene(
                "the terrain around the leg has fewer than 2 x 2 samples".into(),
            ));
        }
        let res = g.resolution_m();
        let origin = Point2::new(
            g.origin().x + x0 as f64 * res,
            g.origin().y + y0 as f64 * res,
        );
        let mut heights = Vec::with_capacity(nx * ny);
        let mut vertices = Vec::with_capacity(nx * ny);
        for iy in 0..ny {
            for ix in 0..nx {
                let h = g.cells()[(y0 + iy) * g.nx() + x0 + ix] + raise_m;
                heights.push(h);
                vertices.push(Vector::new(
                    origin.x + ix as f64 * res,
                    origin.y + iy as f64 * res,
                    h,
                ));
            }
        }
        let mut indices = Vec::with_capacity(2 * (nx - 1) * (ny - 1));
        for iy in 0..ny - 1 {
            for ix in 0..nx - 1 {
                let a = (iy * nx + ix) as u32;
                let b = a + 1;
                let c = a + nx as u32;
                let d = c + 1;
                // Counter-clockwise seen from above: normals point up.
                indices.push([a, b, d]);
                indices.push([a, d, c]);
            }
        }
        let mesh = TriMesh::new(vertices, indices)
            .map_err(|e| FootfallError::Scene(format!("the terrain could not be meshed: {e:?}")))?;
        let levels = build_levels(&heights, nx, ny);
        Ok(TerrainPatch {
            mesh,
            heights,
            origin,
            resolution_m: res,
            nx,
            ny,
            levels,
            raise_m,
        })
    }

    /// How much the patch is raised above the terrain, metres.
    pub fn raise_m(&self) -> f64 {
        self.raise_m
    }

    /// Triangles in the mesh.
    pub fn triangles(&self) -> usize {
        2 * (self.nx - 1) * (self.ny - 1)
    }

    /// The patch's height (raised) at world (x, y), bilinear; edge-clamped outside.
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        let gx = ((x - self.origin.x) / self.resolution_m).clamp(0.0, (self.nx - 1) as f64);
        let gy = ((y - self.origin.y) / self.resolution_m).clamp(0.0, (self.ny - 1) as f64);
        let (ix, iy) = (
            (gx as usize).min(self.nx - 2),
            (gy as usize).min(self.ny - 2),
        );
        let (u, v) = (gx - ix as f64, gy - iy as f64);
        let h = |i: usize, j: usize| self.heights[j * self.nx + i];
        let a = h(ix, iy) + (h(ix + 1, iy) - h(ix, iy)) * u;
        let b = h(ix, iy + 1) + (h(ix + 1, iy + 1) - h(ix, iy + 1)) * u;
        a + (b - a) * v
    }

    /// An upper bound of the patch's height over the square of half-side `r` about `c`.
    pub fn max_over(&self, c: Point2<f64>, r: f64) -> f64 {
        let to_index = |v: f64, o: f64, n: usize| -> usize {
            let g = ((v - o) / self.resolution_m).floor();
            if g.is_nan() {
                0
            } else {
                g.clamp(0.0, (n - 1) as f64) as usize
            }
        };
        let x0 = to_index(c.x - r, self.origin.x, self.nx);
        let x1 = (to_index(c.x + r, self.origin.x, self.nx) + 1).min(self.nx - 1);
        let y0 = to_index(c.y - r, self.origin.y, self.ny);
        let y1 = (to_index(c.y + r, self.origin.y, self.ny) + 1).min(self.ny - 1);
        let span = (x1 - x0).max(y1 - y0) + 1;
        // The smallest level whose blocks cover the span with at most 3 x 3 of them.
        let level = self.levels.iter().find(|l| l.block * 2 >= span);
        match level {
            None => self
                .levels
                .last()
                .map(|l| l.max.iter().copied().fold(f64::NEG_INFINITY, f64::max))
                .unwrap_or(f64::INFINITY),
            Some(l) => {
                let mut best = f64::NEG_INFINITY;
                for by in y0 / l.block..=y1 / l.block {
                    for bx in x0 / l.block..=x1 / l.block {
                        if bx < l.bx && by < l.by {
                            best = best.max(l.max[by * l.bx + bx]);
                        }
                    }
                }
                best
            }
        }
    }

    /// Whether a world point lies inside the patch's rectangle (in XY).
    pub fn covers(&self, x: f64, y: f64) -> bool {
        x >= self.origin.x
            && y >= self.origin.y
            && x <= self.origin.x + (self.nx - 1) as f64 * self.resolution_m
            && y <= self.origin.y + (self.ny - 1) as f64 * self.resolution_m
    }
}

fn build_levels(heights: &[f64], nx: usize, ny: usize) -> Vec<MaxLevel> {
    let mut levels = Vec::new();
    let mut block = 2;
    loop {
        let (bx, by) = (nx.div_ceil(block), ny.div_ceil(block));
        let mut max = vec![f64::NEG_INFINITY; bx * by];
        for iy in 0..ny {
            for ix in 0..nx {
                let b = (iy / block) * bx + ix / block;
                max[b] = max[b].max(heights[iy * nx + ix]);
            }
        }
        levels.push(MaxLevel { block, bx, by, max });
        if bx <= 1 && by <= 1 {
            return levels;
        }
        block *= 2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bumpy() -> HeightField {
        let (nx, ny, res) = (61, 61, 0.05);
        let mut h = Vec::new();
        for iy in 0..ny {
            for ix in 0..nx {
                let (x, y) = (ix as f64 * res, iy as f64 * res);
                h.push(0.3 * (x * 3.0).sin() * (y * 2.0).cos());
            }
        }
        HeightField::new(Point2::origin(), res, nx, ny, h).unwrap()
    }

    #[test]
    fn the_patch_follows_the_terrain_raised() {
        let t = bumpy();
        let p = TerrainPatch::around(&t, Point2::new(1.5, 1.5), 1.0, 0.15).unwrap();
        assert_eq!(p.triangles(), 2 * 40 * 40);
        for (x, y) in [(1.0, 1.0), (1.23, 1.71), (2.4, 0.6)] {
            assert!((p.height_at(x, y) - t.height_at(x, y) - 0.15).abs() < 1e-9);
        }
    }

    #[test]
    fn maxima_bound_every_sample_they_cover() {
        let t = bumpy();
        let p = TerrainPatch::around(&t, Point2::new(1.5, 1.5), 1.4, 0.0).unwrap();
        for (cx, cy, r) in [
            (1.0, 1.0, 0.1),
            (1.5, 1.2, 0.4),
            (0.5, 2.5, 0.9),
            (1.5, 1.5, 3.0),
        ] {
            let bound = p.max_over(Point2::new(cx, cy), r);
            let mut top = f64::NEG_INFINITY;
            let mut x = cx - r;
            while x <= cx + r {
                let mut y = cy - r;
                while y <= cy + r {
                    if p.covers(x, y) {
                        top = top.max(p.height_at(x, y));
                    }
                    y += 0.01;
                }
                x += 0.01;
            }
            assert!(bound >= top - 1e-12, "({cx}, {cy}, {r}): {bound} < {top}");
        }
    }

    #[test]
    fn bad_sizes_are_refused() {
        let t = bumpy();
        assert!(TerrainPatch::around(&t, Point2::new(1.5, 1.5), 0.0, 0.0).is_err());
        assert!(TerrainPatch::around(&t, Point2::new(50.0, 50.0), 1.0, 0.0).is_err());
    }
}
