//! From ray echoes to returns: the echoes of one beam grouped per range cell (summed power, winning
//! instance, echo-weighted elevation), merged with the beam's clutter draws and thresholded.

use crate::geometry::RigidPose;
use crate::scene::NO_HIT;
use crate::sensors::radar::clutter::{CellDraws, ClutterBin};
use crate::sensors::radar::{horizon_elevation, RadarConfig, RadarEnv};
use crate::sensors::radar_model::CLASS_WATER;

/// A target echo in range bin `bin`: one ray's contribution, or a whole cell's (summed power, the instance and
/// class with the largest summed echo, echo-weighted elevation in radians).
#[derive(Debug, Clone, Copy)]
pub(super) struct Echo {
    pub(super) bin: u32,
    pub(super) instance: i32,
    pub(super) class: u16,
    pub(super) power: f64,
    pub(super) elevation: f64,
}

/// Groups the ray echoes of one beam into one echo per cell (sorted by bin).
pub(super) fn group_cells(mut echoes: Vec<Echo>) -> Vec<Echo> {
    echoes.sort_by(|a, b| (a.bin, a.instance).cmp(&(b.bin, b.instance)).then(b.power.total_cmp(&a.power)));
    let mut cells: Vec<Echo> = Vec::new();
    let mut i = 0;
    while i < echoes.len() {
        let bin = echoes[i].bin;
        let mut cell = Echo { bin, power: 0.0, instance: NO_HIT, class: 0, elevation: 0.0 };
        let (mut best, mut weighted_el) = (f64::NEG_INFINITY, 0.0);
        while i < echoes.len() && echoes[i].bin == bin {
            // Within the bin, echoes of one instance are consecutive, strongest ray first.
            let (inst, class) = (echoes[i].instance, echoes[i].class);
            let mut sum = 0.0;
            while i < echoes.len() && echoes[i].bin == bin && echoes[i].instance == inst {
                sum += echoes[i].power;
                weighted_el += echoes[i].power * echoes[i].elevation;
                i += 1;
            }
            cell.power += sum;
            if sum > best {
                best = sum;
                cell.instance = inst;
                cell.class = class;
            }
        }
        cell.elevation = if cell.power > 0.0 { weighted_el / cell.power } else { 0.0 };
        cells.push(cell);
    }
    cells
}

/// Everything one beam's aggregation needs.
pub(super) struct BeamContext<'a> {
    pub(super) cfg: &'a RadarConfig,
    pub(super) env: &'a RadarEnv,
    pub(super) seed: u64,
    pub(super) first: u32,
    pub(super) end: u32,
    pub(super) table: &'a [ClutterBin],
    pub(super) sensor_height: f64,
    /// The physical sea's clutter geometry, when the scene has a wave surface.
    pub(super) physical: Option<crate::sensors::radar::sea_clutter::PhysicalSea>,
    pub(super) pose: &'a RigidPose,
}

/// A finished return before it is split into the parallel arrays.
#[derive(Debug, Clone, Copy)]
pub(super) struct Return {
    pub(super) range: f32,
    pub(super) azimuth: f32,
    pub(super) elevation: f32,
    pub(super) intensity: f32,
    pub(super) instance: i32,
    pub(super) class: u16,
}

impl BeamContext<'_> {
    /// Merges the target cells of beam `b` with its clutter draws into returns, by range bin; `shadowed[i]` of the
    /// beam's `rays_az` azimuth samples do not see the sea in clutter bin `i` (its sea clutter scaled by the share
    /// that does; `shadowed` empty: every sample sees it everywhere).
    pub(super) fn returns(&self, b: u32, cells: &[Echo], shadowed: &[u32]) -> Vec<Return> {
        let mut draws = CellDraws::new(self.seed, b);
        let azimuth = self.cfg.beam_azimuth(b) as f32;
        let horizon = horizon_elevation(self.pose, azimuth as f64).unwrap_or(0.0);
        let mut out = Vec::with_capacity(self.table.len() + cells.len());
        let thr = self.cfg.detection_threshold;
        let mut emit = |bin: u32, target: Option<&Echo>, clutter: Option<ClutterBin>| {
            let (u, w) = draws.at(bin);
            let centre = self.cfg.bin_centre(bin);
            // The still water of this cell lies at elevation `water` in the sensor frame (the clutter's reported
            // elevation): its sea clutter is weighted by the fan's two-way gain there (`pattern`).
            let water = horizon - self.sensor_height.atan2(centre);
            let ClutterBin { mean, sea, p_detect, .. } = clutter
                .unwrap_or_else(|| ClutterBin::at(self.cfg, self.env, self.physical.as_ref(), self.sensor_height, bin))
                .in_view(self.cfg, self.cfg.two_way_gain(water));
            // Clutter alone is detected iff mean · (−ln u) ≥ threshold, i.e. u ≤ exp(−threshold / mean).
            if target.is_none() && u > p_detect {
                return;
            }
            let clutter_power = if mean > 0.0 { mean * -u.ln() } else { 0.0 };
            let target_power = target.map_or(0.0, |t| t.power);
            let total = target_power + clutter_power;
            if !(total > 0.0 && total >= thr) {
                return;
            }
            let noise = self.cfg.range_noise_std_m;
            let range = if noise > 0.0 { (centre + noise * CellDraws::normal(w)).max(0.0) } else { centre };
            let (instance, class, elevation) = match target {
                Some(t) if t.power >= clutter_power => (t.instance, t.class, t.elevation),
                _ => (NO_HIT, if sea { CLASS_WATER } else { 0 }, water),
            };
            out.push(Return {
                range: range as f32,
                azimuth,
                elevation: elevation as f32,
                intensity: total as f32,
                instance,
                class,
            });
        };
        let mut t = 0;
        let samples = self.cfg.rays_az;
        for (i, &c) in self.table.iter().enumerate() {
            let bin = self.first + i as u32;
            let c = match shadowed.get(i) {
                Some(&n) if n > 0 => c.in_view(self.cfg, f64::from(samples - n) / f64::from(samples)),
                _ => c,
            };
            let target = cells.get(t).filter(|cell| cell.bin == bin);
            if target.is_some() {
                t += 1;
            }
            emit(bin, target, Some(c));
        }
        for cell in &cells[t..] {
            if cell.bin < self.end {
                emit(cell.bin, Some(cell), None);
            }
        }
        out
    }
}
