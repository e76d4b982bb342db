//! Image comparison metrics, over all pixels and channels (the images must have the same size):
//! the mean squared error, the relative MSE `mean((x − r)² / (r² + 10⁻²))` (the error relative
//! to the reference value, softened near black, as in the validation against Mitsuba), and the
//! image mean.

use crate::math::Rgb;

/// Mean squared error over pixels and channels.
pub fn mse(image: &[Rgb], reference: &[Rgb]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .map(|(a, b)| {
            let d = (*a - *b).as_dvec3();
            d.length_squared()
        })
        .sum();
    sum / (3 * image.len().max(1)) as f64
}

/// `mean((x - r)² / (r² + 10⁻²))` over pixels and channels.
pub fn relmse(image: &[Rgb], reference: &[Rgb]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .map(|(x, r)| {
            (0..3)
                .map(|c| {
                    let (x, r) = (x[c] as f64, r[c] as f64);
                    (x - r) * (x - r) / (r * r + 1e-2)
                })
                .sum::<f64>()
        })
        .sum();
    sum / (3 * image.len().max(1)) as f64
}

/// Mean over pixels and channels.
pub fn image_mean(image: &[Rgb]) -> f64 {
    image.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>() / (3 * image.len().max(1)) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics() {
        let r = vec![Rgb::splat(1.0), Rgb::splat(0.0)];
        let x = vec![Rgb::splat(1.1), Rgb::splat(0.1)];
        let expected = (0.01 / 1.01 + 0.01 / 0.01) / 2.0;
        assert!((relmse(&x, &r) - expected).abs() < 1e-6);
        assert!((mse(&x, &r) - 0.01).abs() < 1e-6);
        assert!((image_mean(&x) - 0.6).abs() < 1e-6);
        assert_eq!(relmse(&r, &r), 0.0);
    }
}
