//! Counter-based random numbers for sensor noise.
//!
//! Every random draw of a sensor is a pure function of `(seed, stream, index)`: a SplitMix64 hash of the three,
//! so results never depend on how rays are split between threads or in which order they are traced. `stream`
//! separates independent uses (range noise, dropout, water returns, ...) of the same ray index.

/// Named streams, so two noise terms of one ray never share a draw.
pub mod stream {
    /// Gaussian range noise.
    pub const RANGE: u64 = 1;
    /// Random dropout.
    pub const DROPOUT: u64 = 2;
    /// Returns from open water.
    pub const WATER: u64 = 3;
    /// Weather (fog / rain) attenuation losses.
    pub const WEATHER: u64 = 4;
    /// Rain streaks in camera images.
    pub const RAIN: u64 = 5;
    /// Directions and phases of the cameras' fixed four-component swell (the water's normals on a sea without a
    /// wave surface, `Shader::new`).
    pub const RIPPLE: u64 = 6;
    /// The directions of a camera's traced water reflections (`camera/glossy.rs`).
    pub const GLOSSY: u64 = 7;
    /// The rain drops a LiDAR beam meets (`super::lidar_rain`).
    pub const RAIN_DROPS: u64 = 8;
}

#[inline]
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A 64-bit hash of `(seed, stream, index)`.
#[inline(always)]
pub fn hash3(seed: u64, stream: u64, index: u64) -> u64 {
    splitmix64(splitmix64(splitmix64(seed) ^ stream.wrapping_mul(0xD6E8_FEB8_6659_FD93)) ^ index)
}

/// A uniform draw in `[0, 1)` (53 random bits).
#[inline]
pub fn uniform(seed: u64, stream: u64, index: u64) -> f64 {
    (hash3(seed, stream, index) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A standard normal draw (Box–Muller on two uniforms of the same counter).
#[inline]
pub fn normal(seed: u64, stream: u64, index: u64) -> f64 {
    let u1 = uniform(seed, stream, index.wrapping_mul(2)).max(f64::MIN_POSITIVE);
    let u2 = uniform(seed, stream, index.wrapping_mul(2).wrapping_add(1));
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_and_normal_moments() {
        let n = 200_000u64;
        let (mut s, mut s2, mut m) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let u = uniform(7, stream::DROPOUT, i);
            assert!((0.0..1.0).contains(&u));
            m += u;
            let g = normal(7, stream::RANGE, i);
            s += g;
            s2 += g * g;
        }
        let nf = n as f64;
        assert!((m / nf - 0.5).abs() < 0.005);
        assert!((s / nf).abs() < 0.01);
        assert!((s2 / nf - 1.0).abs() < 0.02);
        assert_ne!(hash3(1, 1, 5), hash3(1, 2, 5));
        assert_ne!(hash3(1, 1, 5), hash3(2, 1, 5));
        assert_eq!(hash3(3, 4, 5), hash3(3, 4, 5));
    }
}
