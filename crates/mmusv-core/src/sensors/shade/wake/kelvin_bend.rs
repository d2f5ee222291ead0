//! The Kelvin arms of a wake round its vessel's bends ([`bent_arms`]), for `wake.rs`.
//!
//! They follow the ray theory of ship waves (Lighthill, *Waves in Fluids*, 1978, §3.10,
//! the argument that gives Kelvin's wedge): the waves a vessel at speed `U` sent out `a` seconds ago from a point
//! `P` of its path, heading `ĥ`, are those whose crests kept pace with it (phase speed `U cos θ` at an angle `θ` to
//! `ĥ`); their energy travels at half that speed, so it now lies on a circle of radius `E/4` centred `E/4` ahead of
//! `P` along `ĥ`, `E = Ua` the distance the vessel has gone since. The arms are the envelope of these circles along
//! the path. With `κ` the path's curvature at `P` (to port positive) and `k = Eκ`, the envelope touches the circle of
//! `P` where its normal makes the angle `ψ` with `ĥ` that solves `3 cos ψ + k sin ψ = 1` (the derivative of the
//! family along the path), i.e. `ψ = atan2(k, 3) ± acos(1/√(9 + k²))`, one root per arm. On a straight course (`k =
//! 0`) that is `cos ψ = 1/3`: the wedge of half-angle `asin(1/3)` behind the bow. A vessel's own straight piece draws
//! that wedge as far as the waves it sent out along that piece have gone; round its bends the arms are worked out
//! along the pieces behind it (the heading turning from one piece's to the next's over a stretch round their joint
//! as long as the shorter piece, so along a turn cut into equal chords it runs linearly between the chords'
//! middles, at the turn's curvature) and drawn as straight stretches (`E` counted from where the bow was). Their
//! width and fade are those of a straight course's arms the same `E` behind (`wake.rs`).

use super::{arm_strength, arm_width, Wake, WakeShape, WAKE_FADE_S, WAKE_REACH_S};

/// On a straight course, how far behind the bow the arm point of the waves sent out `e` metres back lies.
#[inline(always)]
fn behind_bow(e: f32) -> f32 {
    e * (2.0 / 3.0)
}

/// A straight stretch of a Kelvin arm bent round the path (module header): from `a` to `b` (world metres), the
/// waves there sent out when the bow was `e[0]`, `e[1]` metres back along the path.
#[derive(Debug, Clone, Copy)]
pub(super) struct ArmSegment {
    a: [f32; 2],
    /// `b − a` and `1 / |b − a|²`.
    ab: [f32; 2],
    inv_len2: f32,
    e: [f32; 2],
    speed: f32,
    length: f32,
    beam: f32,
}

impl ArmSegment {
    fn new(a: [f32; 2], b: [f32; 2], e: [f32; 2], w: &Wake) -> Self {
        let ab = [b[0] - a[0], b[1] - a[1]];
        let len2 = ab[0] * ab[0] + ab[1] * ab[1];
        let inv_len2 = if len2 > 0.0 { 1.0 / len2 } else { 0.0 };
        Self { a, ab, inv_len2, e, speed: w.speed, length: w.length, beam: w.beam }
    }

    /// The nearest point's share along the segment and its distance from `(x, y)`.
    #[inline(always)]
    fn nearest(&self, x: f32, y: f32) -> (f32, f32) {
        let (dx, dy) = (x - self.a[0], y - self.a[1]);
        let t = ((dx * self.ab[0] + dy * self.ab[1]) * self.inv_len2).clamp(0.0, 1.0);
        (t, (dx - t * self.ab[0]).hypot(dy - t * self.ab[1]))
    }

    /// The widest the arm is along this stretch (it widens with `e`).
    fn widest(&self) -> f32 {
        arm_width(behind_bow(self.e[0].max(self.e[1])), self.beam)
    }

    /// Whether any point within `r` of `c` may lie on this stretch.
    pub(super) fn may_reach(&self, c: [f32; 2], r: f32) -> bool {
        self.nearest(c[0], c[1]).1 - r < self.widest()
    }

    /// The foam density this stretch lays at `(x, y)` (0 where none), `noise_at` the foam noise there: as wide
    /// and as faded as the arm of a straight course at the same `e`.
    #[inline(always)]
    pub(super) fn foam_at(&self, x: f32, y: f32, noise_at: &mut impl FnMut() -> f32) -> f32 {
        let (t, d) = self.nearest(x, y);
        let from_bow = behind_bow(self.e[0] + t * (self.e[1] - self.e[0]));
        let width = arm_width(from_bow, self.beam);
        if d >= width {
            return 0.0;
        }
        let fade = (-(from_bow - self.length).max(0.0) / (self.speed * WAKE_FADE_S)).exp();
        let f = (1.0 - d / width) * fade * arm_strength(self.speed) * 0.45;
        (f * (1.6 * noise_at() - 0.3)).clamp(0.0, 1.0)
    }
}

/// The Kelvin arms of the wake whose pieces are `chain`, prepared as `shapes` (its vessel's own first, then older pieces round its
/// bends, each starting where the one before ends), from where the own piece's straight arms end as far as the
/// foam lasts: the envelope of the waves' energy circles along the path (module header), worked out at points
/// along it (every 2 % of the distance back, 2–10 m apart) and joined by straight stretches, left arm then right.
pub(super) fn bent_arms(chain: &[Wake], shapes: &[WakeShape]) -> Vec<ArmSegment> {
    let own = &chain[0];
    if chain.len() < 2 || shapes.len() != chain.len() {
        return Vec::new();
    }
    let (u, length) = (own.speed, own.length);
    // The path back from the vessel's stern: piece k from `q = back_k` (metres of path) to the next piece's
    // start (the last one as far as it reaches, at most 100 km); the pieces' headings unwrapped.
    let starts: Vec<f32> = shapes.iter().map(|s| s.back).collect();
    let ends: Vec<f32> = (0..chain.len())
        .map(|k| if k + 1 < chain.len() { starts[k + 1] } else { starts[k] + chain[k].reach_m.min(1e5) })
        .collect();
    let mut headings = Vec::with_capacity(chain.len());
    for w in chain {
        let mut h = w.heading;
        if let Some(&prev) = headings.last() {
            let prev: f32 = prev;
            h = prev + (h - prev + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI;
        }
        headings.push(h);
    }
    // The heading turns from one piece's to the next's over the stretch round their joint as long as the shorter of
    // the two (so along a turn cut into equal chords the heading runs linearly between the chords' middles, at the
    // turn's curvature), starting at the joint on the own piece (straight by definition).
    let mut anchors: Vec<(f32, f32)> = Vec::with_capacity(2 * chain.len());
    for k in 0..chain.len() - 1 {
        let joint = starts[k + 1];
        let m = 0.5 * (ends[k] - starts[k]).min(ends[k + 1] - starts[k + 1]).max(0.0);
        anchors.push((if k == 0 { joint } else { joint - m }, headings[k]));
        anchors.push((joint + m, headings[k + 1]));
    }
    // Heading at `q`, and its rate going back along the path (rad per metre) on the stretch between anchors that
    // starts at `q` (`after`) or ends there.
    let heading_at = |q: f32, after: bool| -> (f32, f32) {
        let i = anchors.iter().position(|&(aq, _)| if after { aq > q } else { aq >= q });
        match i {
            Some(0) => (anchors[0].1, 0.0),
            None => (anchors[anchors.len() - 1].1, 0.0),
            Some(i) => {
                let ((q0, h0), (q1, h1)) = (anchors[i - 1], anchors[i]);
                let rate = (h1 - h0) / (q1 - q0).max(1e-3);
                (h0 + rate * (q - q0), rate)
            }
        }
    };
    let point_at = |q: f32| -> [f32; 2] {
        let k = (0..chain.len()).rev().find(|&k| starts[k] <= q).unwrap_or(0);
        let s = &shapes[k];
        let b = q - s.back;
        [s.stern[0] - s.dir[0] * b, s.stern[1] - s.dir[1] * b]
    };
    // From the end of the own piece's straight stretch to the foam's end, every 2 % of the way back (2–10 m), and
    // at every anchor twice, with the curvature before and after it (the envelope there goes round the circle of
    // that point from one to the other; a straight stretch joins them).
    let q_max = (u * WAKE_REACH_S - length).min(ends[chain.len() - 1]);
    let mut samples: Vec<(f32, bool)> = Vec::new();
    let mut q = ends[0];
    let mut next_anchor = 0;
    while q <= q_max {
        while next_anchor < anchors.len() && anchors[next_anchor].0 <= q {
            let aq = anchors[next_anchor].0;
            if aq >= ends[0] && aq <= q_max {
                samples.push((aq, false));
                samples.push((aq, true));
            }
            next_anchor += 1;
        }
        if samples.last().is_none_or(|&(last, _)| last < q) {
            samples.push((q, true));
        }
        q += (0.02 * (q + length)).clamp(2.0, 10.0);
    }
    let mut sides: [Vec<([f32; 2], f32)>; 2] = [Vec::new(), Vec::new()];
    for (q, after) in samples {
        let e = q + length;
        let p = point_at(q);
        let (h, back_rate) = heading_at(q, after);
        // Forward curvature κ = −dθ/dq; with k = E κ the normal to the envelope is at ψ = φ ± acos(1/√(9 + k²))
        // from the heading, φ = atan2(k, 3) (3 cos ψ + k sin ψ = 1).
        let k = -e * back_rate;
        let (phi, spread) = (k.atan2(3.0), (1.0 / (9.0 + k * k).sqrt()).acos());
        let (sh, ch) = h.sin_cos();
        for (side, psi) in [(0, phi + spread), (1, phi - spread)] {
            let (sp, cp) = psi.sin_cos();
            // n = cos ψ ĥ + sin ψ ĥ⊥ (ĥ⊥ to port); the point: P + (E/4)(ĥ + n).
            let n = [cp * ch - sp * sh, cp * sh + sp * ch];
            sides[side].push(([p[0] + 0.25 * e * (ch + n[0]), p[1] + 0.25 * e * (sh + n[1])], e));
        }
    }
    // Runs of points within 5 cm of the straight stretch between their ends are drawn as that one stretch (the
    // straight legs of a path give long runs).
    let mut out = Vec::new();
    for pts in &sides {
        let mut from = 0;
        while from + 1 < pts.len() {
            let mut to = from + 1;
            while to + 1 < pts.len() && (from + 1..=to).all(|m| off_line(pts[m].0, pts[from].0, pts[to + 1].0) <= 0.05)
            {
                to += 1;
            }
            out.push(ArmSegment::new(pts[from].0, pts[to].0, [pts[from].1, pts[to].1], own));
            from = to;
        }
    }
    out
}

/// How far `p` lies from the straight stretch from `a` to `b` (metres).
fn off_line(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f32 {
    let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 { ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}

#[cfg(test)]
mod tests {
    use super::super::super::foam::Foam;
    use super::super::tests::same_cover;
    use super::super::{Wake, Wakes};

    /// Round a bend the Kelvin arms are the envelope of the waves sent out along the path (module header), worked
    /// out here by brute force: the boundary of the union of the energy circles (centre `P + Eĥ/4`, radius `E/4`)
    /// sent out every 0.25 m along the smooth path itself, a quarter circle of radius 60 m between two straight legs.
    /// Every point of that boundary from 15 m behind the stern on lies on an arm drawn from the wake's pieces (the
    /// own piece and 15° chords of the turn, as `Simulation.wakes` gives them), and farther than 10 m outside it
    /// there is no foam;
    /// indexed around a sensor, the same cover to the bit. (Before, the arms ended at the bend: no foam along the
    /// boundary round and before the turn.)
    #[test]
    fn kelvin_arms_round_a_bend_follow_the_envelope_of_the_waves_sent_out() {
        use std::f64::consts::FRAC_PI_2;
        // Heading east along y = 0, then a quarter turn to port round (0, 60), then north; the stern is now at
        // (60, 120), 60 m past the turn.
        let (u, length, beam, rho) = (10.0f64, 20.0f64, 5.0f64, 60.0f64);
        let arc = |t: f64| [rho * t.sin(), rho * (1.0 - t.cos())];
        let row = |stern: [f64; 2], heading: f64, reach: f64, back: f64| Wake {
            x: (stern[0] + 0.5 * length * heading.cos()) as f32,
            y: (stern[1] + 0.5 * length * heading.sin()) as f32,
            heading: heading as f32,
            speed: u as f32,
            length: length as f32,
            beam: beam as f32,
            reach_m: reach as f32,
            age_s: (back / u) as f32,
            goes_on: true,
            displacement_m3: 0.0,
        };
        let mut rows = vec![row([60.0, 120.0], FRAC_PI_2, 60.0, 0.0)];
        let step = 15f64.to_radians();
        for j in 0..6 {
            let (t0, t1) = (FRAC_PI_2 - f64::from(j) * step, FRAC_PI_2 - f64::from(j + 1) * step);
            let (a, b) = (arc(t0), arc(t1));
            rows.push(row(a, 0.5 * (t0 + t1), (a[0] - b[0]).hypot(a[1] - b[1]), 60.0 + rho * f64::from(j) * step));
        }
        rows.push(row([0.0, 0.0], 0.0, 2000.0, 60.0 + rho * FRAC_PI_2));
        let wakes = Wakes::new(&rows);
        let density = |x: f64, y: f64| wakes.cover(x as f32, y as f32, &mut || 1.0);
        // The energy circles of the smooth path: (centre, radius) per point sent out; E from the bow.
        let mut circles: Vec<([f64; 2], f64)> = Vec::new();
        let mut add = |p: [f64; 2], h: f64, e: f64| {
            circles.push(([p[0] + 0.25 * e * h.cos(), p[1] + 0.25 * e * h.sin()], 0.25 * e));
        };
        for i in 0..=320 {
            let b = -20.0 + 0.25 * f64::from(i); // behind the stern, from the bow to the turn
            add([60.0, 120.0 - b], FRAC_PI_2, length + b);
        }
        let turn = rho * FRAC_PI_2;
        for i in 0..=(turn / 0.25) as usize {
            let s = 0.25 * i as f64;
            let t = FRAC_PI_2 - s / rho;
            add(arc(t), t, length + 60.0 + s);
        }
        for i in 0..=4000 {
            let b = 0.25 * f64::from(i);
            add([-b, 0.0], 0.0, length + 60.0 + turn + b);
        }
        let inside = |x: [f64; 2]| circles.iter().any(|(c, r)| (x[0] - c[0]).hypot(x[1] - c[1]) < *r);
        // How far a point outside the union is from it.
        let gap =
            |x: [f64; 2]| circles.iter().map(|(c, r)| (x[0] - c[0]).hypot(x[1] - c[1]) - r).fold(f64::MAX, f64::min);
        // The first way out of the union from a point inside along a direction (to 0.02 m).
        let exit = |from: [f64; 2], dir: [f64; 2]| {
            let at = |t: f64| [from[0] + t * dir[0], from[1] + t * dir[1]];
            let mut t = 0.0;
            while inside(at(t + 0.5)) {
                t += 0.5;
            }
            let (mut lo, mut hi) = (t, t + 0.5);
            while hi - lo > 0.02 {
                let mid = 0.5 * (lo + hi);
                if inside(at(mid)) {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            at(lo)
        };
        let mut rays: Vec<([f64; 2], [f64; 2])> = Vec::new();
        for y0 in [70.0, 85.0, 105.0] {
            rays.push(([60.0, y0], [1.0, 0.0]));
            rays.push(([60.0, y0], [-1.0, 0.0]));
        }
        for deg in [10.0f64, 30.0, 45.0, 60.0, 80.0] {
            let t = deg.to_radians();
            rays.push((arc(t), [t.sin(), -t.cos()])); // outside the turn
            rays.push((arc(t), [-t.sin(), t.cos()])); // inside
        }
        for x0 in [-30.0, -100.0, -200.0, -300.0] {
            rays.push(([x0, 0.0], [0.0, -1.0]));
            rays.push(([x0, 0.0], [0.0, 1.0]));
        }
        let mut beyond = 0;
        for (from, dir) in rays {
            let b = exit(from, dir);
            assert!(density(b[0], b[1]) > 0.0, "the envelope at ({:.2}, {:.2}) (from {from:?}) has no arm", b[0], b[1]);
            // Well outside the union (farther from every circle than the widest arm here, 10 m), no foam.
            let out = [b[0] + 25.0 * dir[0], b[1] + 25.0 * dir[1]];
            if gap(out) > 10.0 {
                assert_eq!(density(out[0], out[1]), 0.0, "beyond the envelope at {out:?}");
                beyond += 1;
            }
        }
        assert!(beyond >= 10, "{beyond}");
        assert!(wakes.arms.len() > 20, "{}", wakes.arms.len());
        // Between the outer arm and the track before the turn, inside the envelope: no foam.
        for x0 in [-200.0, -300.0] {
            let arm = exit([x0, 0.0], [0.0, -1.0])[1];
            assert_eq!(density(x0, 0.5 * arm), 0.0);
        }
        // Indexed around a sensor: the same cover to the bit.
        let foam = Foam::new(0.0, &rows, 5);
        let indexed = foam.clone().around([0.0, 50.0], 400.0);
        let foamy = same_cover(&foam, &indexed, 6, [-500.0, -400.0], 900.0);
        assert!(foamy > 1_000, "{foamy}");
    }
}
