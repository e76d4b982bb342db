//! Perlin's gradient noise and its sums (fractional Brownian motion, turbulence), as pbrt-v4
//! defines them for its procedural textures (`fbm`, `wrinkled`, `windy`, `marble`, `dots`).
//!
//! The lattice is Perlin's: 256 gradient choices indexed by his permutation table, the
//! twelve edge directions of a cube (four repeated) picked by the low four bits of the hash,
//! weights blended by the quintic `6t⁵ − 15t⁴ + 10t³`. The noise is 0 at every lattice point
//! and lies in about [−1, 1]; its period is 256 along each axis. Sums of octaves follow pbrt-v4:
//! frequencies grow by 1.99 per octave (not 2, so that lattices do not line up), amplitudes by
//! `omega`. pbrt narrows the sum to the octaves a pixel footprint resolves (ray
//! differentials); neumann has no footprints and sums every octave — the limit pbrt reaches
//! for footprints below 2^−(octaves+1), and, for wider ones, the same image once the pixel's
//! samples average the finest octaves out.

use crate::math::Vec3;

/// Perlin's permutation of 0..=255 (his reference implementation's), used twice over so that
/// `PERM[PERM[x] + y]` needs no wrap.
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37, 240,
    21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88,
    237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83,
    111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216,
    80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186,
    3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17,
    182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129,
    22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238,
    210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184,
    84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195,
    78, 66, 215, 61, 156, 180,
];

/// The permutation extended periodically (index < 512).
#[inline]
fn perm(i: usize) -> usize {
    PERM[i & 255] as usize
}

/// The gradient at lattice point (x, y, z) dotted with the offset (dx, dy, dz) from it.
#[inline]
fn grad(x: usize, y: usize, z: usize, dx: f32, dy: f32, dz: f32) -> f32 {
    let h = perm(perm(perm(x) + y) + z) & 15;
    let u = if h < 8 || h == 12 || h == 13 { dx } else { dy };
    let v = if h < 4 || h == 12 || h == 13 { dy } else { dz };
    (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
}

/// Perlin's quintic blend `6t⁵ − 15t⁴ + 10t³` (zero first and second derivatives at 0 and 1).
#[inline]
fn blend(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// Perlin noise at `p`: 0 on the integer lattice, about [−1, 1] elsewhere, period 256.
/// Coordinates are first reduced modulo 2³⁰, as pbrt does, so that huge ones stay finite.
pub fn noise(p: Vec3) -> f32 {
    const WRAP: f32 = (1u32 << 30) as f32;
    let p = Vec3::new(p.x % WRAP, p.y % WRAP, p.z % WRAP);
    if !p.is_finite() {
        return 0.0;
    }
    let c = p.map(crate::math::floor);
    let d = p - c;
    let (ix, iy, iz) = ((c.x as i64 & 255) as usize, (c.y as i64 & 255) as usize, (c.z as i64 & 255) as usize);
    let w = |ox: usize, oy: usize, oz: usize| {
        grad(ix + ox, iy + oy, iz + oz, d.x - ox as f32, d.y - oy as f32, d.z - oz as f32)
    };
    let (wx, wy, wz) = (blend(d.x), blend(d.y), blend(d.z));
    let x00 = lerp(wx, w(0, 0, 0), w(1, 0, 0));
    let x10 = lerp(wx, w(0, 1, 0), w(1, 1, 0));
    let x01 = lerp(wx, w(0, 0, 1), w(1, 0, 1));
    let x11 = lerp(wx, w(0, 1, 1), w(1, 1, 1));
    lerp(wz, lerp(wy, x00, x10), lerp(wy, x01, x11))
}

/// Fractional Brownian motion: `Σᵢ omegaⁱ noise(1.99ⁱ p)` over `octaves` octaves.
pub fn fbm(p: Vec3, omega: f32, octaves: u32) -> f32 {
    let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
    for _ in 0..octaves {
        sum += o * noise(lambda * p);
        lambda *= 1.99;
        o *= omega;
    }
    sum
}

/// Turbulence: `Σᵢ omegaⁱ |noise(1.99ⁱ p)|` over `octaves` octaves, plus pbrt-v4's allowance
/// for the octaves beyond them (`0.2 omega^octaves`, what it adds at a full octave count).
pub fn turbulence(p: Vec3, omega: f32, octaves: u32) -> f32 {
    let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
    for _ in 0..octaves {
        sum += o * noise(lambda * p).abs();
        lambda *= 1.99;
        o *= omega;
    }
    sum + o * 0.2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    #[test]
    fn the_table_is_a_permutation() {
        let mut seen = [false; 256];
        for &v in PERM.iter() {
            assert!(!seen[v as usize], "{v} twice");
            seen[v as usize] = true;
        }
    }

    /// Zero on the lattice, bounded, continuous, periodic with period 256, mean about zero,
    /// and varied (a noise stuck at a constant, or with a broken hash, fails one of these).
    #[test]
    fn noise_properties() {
        for (x, y, z) in [(0, 0, 0), (3, -7, 12), (255, 1, 300)] {
            assert_eq!(noise(Vec3::new(x as f32, y as f32, z as f32)), 0.0);
        }
        let mut rng = Pcg32::new(7, 1);
        let (mut sum, mut sum2, n) = (0.0f64, 0.0f64, 20_000);
        for _ in 0..n {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 40.0 - 20.0;
            let v = noise(p);
            assert!(v.abs() <= 1.1, "{v} at {p}");
            let h = 1e-3;
            assert!((noise(p + Vec3::splat(h)) - v).abs() < 0.02, "continuity at {p}");
            assert!((noise(p + Vec3::new(256.0, -256.0, 512.0)) - v).abs() < 1e-3, "period at {p}");
            sum += v as f64;
            sum2 += (v * v) as f64;
        }
        let mean = sum / n as f64;
        let var = sum2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!(var > 0.02 && var < 0.2, "variance {var}");
        // The gradient of the cell at the origin: hash of (0,0,0) is PERM[PERM[PERM[0]]] & 15.
        let h = perm(perm(perm(0))) & 15;
        let eps = 1e-3;
        let g = noise(Vec3::new(eps, 0.0, 0.0)) / eps;
        let expected = match h {
            0..=7 | 12 | 13 => {
                if h & 1 != 0 {
                    -1.0
                } else {
                    1.0
                }
            }
            _ => 0.0,
        };
        // The quintic blend is flat at 0, so near the corner the noise is the corner's linear term.
        assert!((g - expected).abs() < 1e-2, "∂noise/∂x at the origin {g}, expected {expected} (hash {h})");
    }

    #[test]
    fn sums_of_octaves() {
        let p = Vec3::new(0.3, 1.7, -2.2);
        assert_eq!(fbm(p, 0.5, 1), noise(p));
        let two = noise(p) + 0.5 * noise(1.99 * p);
        assert!((fbm(p, 0.5, 2) - two).abs() < 1e-6);
        let t = noise(p).abs() + 0.5 * noise(1.99 * p).abs() + 0.25 * 0.2;
        assert!((turbulence(p, 0.5, 2) - t).abs() < 1e-6);
        assert!(turbulence(p, 0.5, 8) > 0.0);
        assert!(noise(Vec3::splat(f32::NAN)) == 0.0 && noise(Vec3::splat(1e30)).is_finite());
    }
}
