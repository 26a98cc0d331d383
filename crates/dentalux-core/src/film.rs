//! The film: one float32 radiance image per band (H × W, row-major, row 0 at the top), and
//! the tiling that renders fill it in parallel and deterministically.

/// Side of a square tile [pixels].
pub const TILE: usize = 16;

/// A rectangle of pixels [x0, x1) × [y0, y1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    /// Tile index (row-major over the tile grid): it keys the tile's random stream.
    pub index: u64,
    /// First column.
    pub x0: usize,
    /// One past the last column.
    pub x1: usize,
    /// First row.
    pub y0: usize,
    /// One past the last row.
    pub y1: usize,
}

/// One band's image.
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    /// Width [pixels].
    pub width: usize,
    /// Height [pixels].
    pub height: usize,
    /// Radiance per pixel, row-major.
    pub data: Vec<f32>,
}

impl Film {
    /// A black film.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }
    /// The tiles covering the film, in index order.
    pub fn tiles(&self) -> Vec<Tile> {
        let (nx, ny) = (self.width.div_ceil(TILE), self.height.div_ceil(TILE));
        (0..nx * ny)
            .map(|i| {
                let (tx, ty) = (i % nx, i / nx);
                Tile {
                    index: i as u64,
                    x0: tx * TILE,
                    x1: ((tx + 1) * TILE).min(self.width),
                    y0: ty * TILE,
                    y1: ((ty + 1) * TILE).min(self.height),
                }
            })
            .collect()
    }
    /// Write a tile's pixels (row-major within the tile).
    pub fn put(&mut self, tile: &Tile, pixels: &[f32]) {
        let w = tile.x1 - tile.x0;
        for (r, y) in (tile.y0..tile.y1).enumerate() {
            let row = &pixels[r * w..(r + 1) * w];
            self.data[y * self.width + tile.x0..y * self.width + tile.x1].copy_from_slice(row);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_every_pixel_once() {
        let mut f = Film::new(37, 20);
        let tiles = f.tiles();
        assert_eq!(tiles.len(), 3 * 2);
        for t in &tiles {
            let n = (t.x1 - t.x0) * (t.y1 - t.y0);
            let px: Vec<f32> = vec![1.0; n];
            let old: Vec<f32> = f.data.clone();
            f.put(t, &px);
            assert_eq!(f.data.iter().zip(&old).filter(|(a, b)| a != b).count(), n);
        }
        assert!(f.data.iter().all(|&v| v == 1.0));
    }
}
