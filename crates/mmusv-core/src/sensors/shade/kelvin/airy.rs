//! The Airy function `Ai` and its derivative on the real line, for the Kelvin waves' caustic
//! ([`super::KelvinWaves`]).
//!
//! Method: the Maclaurin series for `|x| ≤ 5` (NIST DLMF §9.4.1, with `Ai(0)`, `Ai'(0)` of §9.2.3; tabulated once
//! and interpolated) and the
//! asymptotic expansions beyond, three terms (DLMF §9.7.5–9.7.6 for `x → +∞`, §9.7.9–9.7.10 for `x → −∞`);
//! checked against tabulated values (DLMF Table 9.9.1 and the standard references) in the tests.

/// `Ai(0)`.
pub(super) const AI_0: f64 = 0.355_028_053_887_817_2;
/// The largest value of `Ai`, at `x = −1.0188`.
pub(super) const AI_MAX: f64 = 0.535_656_656_015_700_3;
/// `−Ai'(0)`.
const DAI_0: f64 = 0.258_819_403_792_806_8;
/// Where the series gives way to the asymptotic expansions.
const SERIES_LIMIT: f64 = 5.0;
/// `1/√π`.
const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;
/// The coefficients `u₁`, `u₂`, `u₃` and `v₁`, `v₂`, `v₃` of DLMF §9.7.
const U: [f64; 3] = [0.069_444_444_444_444_44, 0.037_133_487_654_320_99, 0.037_993_059_127_800_47];
const V: [f64; 3] = [-0.097_222_222_222_222_22, -0.043_885_030_864_197_53, -0.042_462_830_789_394_6];

/// Nodes per unit of the table the series fills for `|x| ≤ 5`, read by cubic Hermite interpolation (values and
/// slopes at the nodes, `Ai'' = x Ai`): within 10⁻⁹ of the series, a few multiplications instead of its terms.
const TABLE_PER_UNIT: f64 = 128.0;

/// `(Ai(x), Ai'(x))` at the table's nodes `x = −5 + i / TABLE_PER_UNIT`.
fn table() -> &'static [(f64, f64)] {
    static TABLE: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let n = (2.0 * SERIES_LIMIT * TABLE_PER_UNIT) as usize;
        (0..=n).map(|i| series(-SERIES_LIMIT + i as f64 / TABLE_PER_UNIT)).collect()
    })
}

/// `(Ai(x), Ai'(x))` for `|x| ≤ 5` from the table: cubic Hermite on `Ai` (slopes `Ai'`) and on `Ai'` (slopes
/// `Ai'' = x Ai`).
#[inline]
fn tabulated(x: f64) -> (f64, f64) {
    let t = table();
    let u = (x + SERIES_LIMIT) * TABLE_PER_UNIT;
    let i = (u.floor() as usize).min(t.len() - 2);
    let f = u - i as f64;
    let h = 1.0 / TABLE_PER_UNIT;
    let (x0, x1) = (-SERIES_LIMIT + i as f64 * h, -SERIES_LIMIT + (i + 1) as f64 * h);
    let ((a0, d0), (a1, d1)) = (t[i], t[i + 1]);
    let (f2, f3) = (f * f, f * f * f);
    let (h00, h10, h01, h11) = (2.0 * f3 - 3.0 * f2 + 1.0, f3 - 2.0 * f2 + f, -2.0 * f3 + 3.0 * f2, f3 - f2);
    let ai = h00 * a0 + h10 * h * d0 + h01 * a1 + h11 * h * d1;
    let dai = h00 * d0 + h10 * h * (x0 * a0) + h01 * d1 + h11 * h * (x1 * a1);
    (ai, dai)
}

/// `(Ai(x), Ai'(x))`.
pub(super) fn airy(x: f64) -> (f64, f64) {
    if x.abs() <= SERIES_LIMIT {
        tabulated(x)
    } else if x > 0.0 {
        let xi = 2.0 / 3.0 * x * x.sqrt();
        let e = (-xi).exp() * 0.5 * FRAC_1_SQRT_PI;
        let q = x.sqrt().sqrt();
        let (mut a, mut d, mut p) = (1.0, 1.0, 1.0);
        for k in 0..3 {
            p *= -1.0 / xi;
            a += U[k] * p;
            d += V[k] * p;
        }
        (e / q * a, -e * q * d)
    } else {
        let z = -x;
        let xi = 2.0 / 3.0 * z * z.sqrt();
        let (s, c) = (xi - std::f64::consts::FRAC_PI_4).sin_cos();
        let q = z.sqrt().sqrt();
        // Even terms with cos (Ai) / sin (Ai'), odd with sin / cos, alternating in pairs.
        let (ae, ao) = (1.0 - U[1] / (xi * xi), U[0] / xi - U[2] / (xi * xi * xi));
        let (de, dodd) = (1.0 - V[1] / (xi * xi), V[0] / xi - V[2] / (xi * xi * xi));
        (FRAC_1_SQRT_PI / q * (c * ae + s * ao), FRAC_1_SQRT_PI * q * (s * de - c * dodd))
    }
}

/// The Maclaurin series `Ai(x) = Ai(0) f(x) + Ai'(0) g(x)`, `f = Σ 3ᵏ (1/3)ₖ x³ᵏ / (3k)!`,
/// `g = Σ 3ᵏ (2/3)ₖ x³ᵏ⁺¹ / (3k+1)!`, and its derivative term by term.
fn series(x: f64) -> (f64, f64) {
    let x3 = x * x * x;
    let (mut f, mut g, mut df, mut dg) = (0.0, 0.0, 0.0, 0.0);
    // Terms of f: x³ᵏ·c_k, derivative 3k x³ᵏ⁻¹ c_k; of g: x³ᵏ⁺¹ d_k, derivative (3k+1) x³ᵏ d_k.
    let (mut tf, mut tg) = (1.0f64, 1.0f64); // c_k x³ᵏ and d_k x³ᵏ
    let mut dtf = 0.0f64; // c_k 3k x³ᵏ⁻¹
    for k in 0..60 {
        let kf = f64::from(k);
        f += tf;
        g += tg * x;
        df += dtf;
        dg += tg * (3.0 * kf + 1.0);
        let nf = tf * x3 / ((3.0 * kf + 2.0) * (3.0 * kf + 3.0));
        dtf = tf * x * x / (3.0 * kf + 2.0);
        tf = nf;
        tg *= x3 / ((3.0 * kf + 3.0) * (3.0 * kf + 4.0));
        if tf.abs() < 1e-18 && tg.abs() < 1e-18 && dtf.abs() < 1e-18 {
            break;
        }
    }
    (AI_0 * f - DAI_0 * g, AI_0 * df - DAI_0 * dg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn airy_matches_tabulated_values() {
        // (x, Ai(x), Ai'(x)) from SciPy's `scipy.special.airy` (Cephes), an independent implementation.
        let table = [
            (0.0, 0.355_028_053_887_817_2, -0.258_819_403_792_806_8),
            (1.0, 0.135_292_416_312_881_47, -0.159_147_441_296_793_28),
            (-1.0, 0.535_560_883_292_352_2, -0.010_160_567_116_645_175),
            (-2.0, 0.227_407_428_201_685_64, 0.618_259_020_741_691),
            (-4.99, 0.353_945_036_684_207_8, 0.309_592_078_959_287_86),
            (-5.0, 0.350_761_009_024_114_2, 0.327_192_818_554_443_6),
            (-5.01, 0.347_401_608_712_205_77, 0.344_665_038_811_839_74),
            (2.0, 0.034_924_130_423_274_36, -0.053_090_384_433_653_88),
            (-7.5, 0.321_775_716_380_647_9, 0.318_809_506_698_554_23),
            (-10.0, 0.040_241_238_486_441_955, 0.996_265_044_132_790_5),
            (-30.0, -0.087_968_188_456_840_05, 1.228_620_602_637_489_5),
            (6.0, 9.947_694_360_252_897e-6, -2.476_520_039_703_497_2e-5),
            (-1.018_792_971_647_471, AI_MAX, 0.0),
        ];
        for (x, a, d) in table {
            let (ai, dai) = airy(x);
            assert!((ai - a).abs() <= 2e-4 * a.abs().max(1e-3), "Ai({x}) = {ai}, not {a}");
            assert!((dai - d).abs() <= 2e-4 * d.abs().max(1e-3), "Ai'({x}) = {dai}, not {d}");
        }
    }

    #[test]
    fn series_and_asymptotics_meet_at_the_limit() {
        for x in [-SERIES_LIMIT, SERIES_LIMIT] {
            let (a, d) = series(x);
            let e = if x < 0.0 { x - 1e-9 } else { x + 1e-9 };
            let (b, f) = airy(e);
            assert!((a - b).abs() < 1e-4 * a.abs().max(1e-3), "{x}: {a} {b}");
            assert!((d - f).abs() < 1e-4 * d.abs().max(1e-3), "{x}: {d} {f}");
        }
    }

    #[test]
    fn the_table_reads_the_series() {
        for i in 0..10_000 {
            let x = -5.0 + 10.0 * f64::from(i) / 9_999.0;
            let (a, d) = series(x);
            let (b, e) = tabulated(x);
            assert!((a - b).abs() < 1e-9 && (d - e).abs() < 1e-8, "{x}: {a} {b} {d} {e}");
        }
    }

    #[test]
    fn the_derivative_is_the_slope() {
        for x in [-9.0, -6.2, -3.3, -0.7, 0.4, 2.5, 5.5] {
            let h = 1e-5;
            let num = (airy(x + h).0 - airy(x - h).0) / (2.0 * h);
            assert!((airy(x).1 - num).abs() < 1e-4 * (1.0 + num.abs()), "{x}: {} {num}", airy(x).1);
        }
    }
}
