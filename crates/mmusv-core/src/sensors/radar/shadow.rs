//! Where a beam sees the sea: sea clutter comes from the water the antenna sees, not from land, nor from the sea in
//! the shadow of an island, a quay or a ship.
//!
//! The still water at range `r` lies, seen from an antenna `h` above it, at the elevation `e_r = e_h − atan(h / r)`
//! (`e_h` the sea horizon's elevation at that azimuth in the sensor frame, as for the clutter returns' own
//! elevation). What stands on the water (islands, quays, hulls) fills everything from the water up to its top, so a
//! ray at elevation `e ≥ e_r` that stopped on something at a distance `d < r` shows that the line to the water at
//! `r`, which passes lower at `d`, is blocked too: the water at `r` is in that object's shadow (or under it, for the
//! land itself). Each azimuth sample of a beam (`rays_az` of them) sees the sea at `r` unless one of its rays at or
//! below the horizon and at or above `e_r` stopped on something (not water) closer than `r` and beyond the blind
//! range (the own ship); a cell's sea clutter is its mean times the share of the beam's samples that see the sea
//! there (geometric shadowing, as the radar's own echoes are). The rays are those the sweep casts anyway, so a low
//! object that no ray met casts no shadow; the crests are water and shadow nothing here (their shadowing of the
//! troughs is in the NRL model's σ⁰). Rain clutter, from the air above, is not shadowed.
//!
//! The model is geometric visibility (line of sight from the antenna), the approach of Billingsley, J. B. (2002),
//! *Low-Angle Radar Land Clutter: Measurements and Empirical Models* (William Andrew / SciTech), ch. 4, whose
//! site-specific clutter model captures the patchiness of low-angle clutter "via deterministic computation of
//! geometric terrain visibility from the radar site" (there from digitized terrain elevation data, here from the
//! sweep's own rays). Beyond that principle the details are the project's: a shadowed share of the beam returns
//! no sea clutter at all (no diffraction into the shadow, no multipath), `e_h` is the sensor's horizontal plane and
//! the still water's depression the flat-earth `atan(h / r)` (the clutter's own grazing angle keeps the 4/3-earth
//! model).
//! The crests' shadowing of the troughs, left to σ⁰ here, is the other, statistical shadowing of sea clutter
//! models (Ward, Tough & Watts, *Sea Clutter: Scattering, the K Distribution and Radar Performance*, §3.6–3.8:
//! negligible at 10° grazing, below it a loss of 4 dB per decade in their composite model).

/// The rays of one azimuth sample that stopped on something other than water: `(elevation, distance)` in the
/// sensor frame (radians, metres), kept only at or below the horizon and beyond the blind range.
#[derive(Debug, Default)]
pub(super) struct Blockers {
    rays: Vec<(f64, f64)>,
}

impl Blockers {
    /// Forgets the rays of the previous sample.
    pub(super) fn clear(&mut self) {
        self.rays.clear();
    }

    /// A ray at `elevation` that stopped `distance` metres out on something that is not water.
    pub(super) fn push(&mut self, elevation: f64, distance: f64) {
        self.rays.push((elevation, distance));
    }

    /// Adds 1 to `shadowed[i]` for every clutter bin `i` whose water this sample does not see, its sea horizon at
    /// elevation `horizon`; `ranges[i]` is the bin's range (increasing) and `depression[i]` the still water's
    /// depression there, `atan(h / ranges[i])` for the antenna `h` above it. `shadowed` is sized (zeros) on the
    /// first shadow; a sample that stopped on nothing leaves it as it is.
    pub(super) fn count_shadowed(&mut self, horizon: f64, ranges: &[f64], depression: &[f64], shadowed: &mut Vec<u32>) {
        let n = self.rays.len();
        if n == 0 {
            return;
        }
        // Ascending elevation; each ray then holds the nearest stop among the rays at or above its elevation.
        self.rays.sort_by(|a, b| a.0.total_cmp(&b.0));
        for i in (0..n - 1).rev() {
            self.rays[i].1 = self.rays[i].1.min(self.rays[i + 1].1);
        }
        // Nothing before the nearest stop is shadowed; the water's elevation rises with range, so once it is above
        // every ray's, nothing after is.
        let mut p = 0;
        for i in ranges.partition_point(|&r| r <= self.rays[0].1)..ranges.len() {
            let e_r = horizon - depression[i];
            while p < n && self.rays[p].0 < e_r {
                p += 1;
            }
            if p == n {
                break;
            }
            if self.rays[p].1 < ranges[i] {
                if shadowed.is_empty() {
                    shadowed.resize(ranges.len(), 0);
                }
                shadowed[i] += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against its definition, ray by ray: a bin is shadowed when some ray with `e_r ≤ e` stopped before it.
    #[test]
    fn sea_in_view_is_the_rule_ray_by_ray() {
        let (horizon, h) = (0.01f64, 5.0f64);
        let ranges: Vec<f64> = (0..200).map(|k| 10.5 + 3.0 * k as f64).collect();
        let mut state = 7u64;
        let mut uni = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..50 {
            let rays: Vec<(f64, f64)> =
                (0..(uni() * 6.0) as usize).map(|_| (horizon - 0.3 * uni(), 10.0 + 600.0 * uni())).collect();
            let mut b = Blockers::default();
            rays.iter().for_each(|&(e, d)| b.push(e, d));
            let depression: Vec<f64> = ranges.iter().map(|&r| h.atan2(r)).collect();
            let mut shadowed = Vec::new();
            b.count_shadowed(horizon, &ranges, &depression, &mut shadowed);
            assert_eq!(
                shadowed.is_empty(),
                rays.iter().all(|&(e, d)| ranges.iter().all(|&r| d >= r || e < horizon - (h / r).atan()))
            );
            shadowed.resize(ranges.len(), 0);
            for (i, &r) in ranges.iter().enumerate() {
                let e_r = horizon - (h / r).atan();
                let dark = rays.iter().any(|&(e, d)| e >= e_r && d < r);
                assert_eq!(shadowed[i], u32::from(dark), "r = {r}, rays {rays:?}");
            }
        }
    }
}
