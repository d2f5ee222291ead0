//! The displaced sea surface in a [`Scene`]: while a [`WaveSurface`] is set, it stands in for the declared sea
//! instance's flat mesh for every ray (closest hits, shadow rays, packets), reported as hits on that instance
//! with the surface's piece as the triangle index; normals come from the piece, the class and material from the
//! sea mesh.

use super::{Hit, Scene};
use crate::bvh::{Packet, PACKET};
use crate::error::{MmusvError, Result};
use crate::ray::{RayPrep, LEAVES_NO, LEAVES_UNKNOWN, LEAVES_YES};
use crate::sea::{WaterHit, WaveSurface};
use parry3d::math::Vec3;
use std::sync::Arc;

impl Scene {
    /// Sets (or with `None` clears) the displaced sea surface of the current frame. The scene must have a sea
    /// ([`Scene::set_sea`]): the surface replaces that instance's flat mesh for every ray, and the sea shortcuts
    /// learn its crest bound ([`WaveSurface::zmax`]). [`Scene::set_sea`] and [`Scene::clear_sea`] clear it.
    /// A surface sampled from a non-finite time, level, focus or component (one no ray would meet) is an input
    /// error naming `surface`.
    pub fn set_wave_surface(&mut self, surface: Option<WaveSurface>) -> Result<()> {
        let Some(sea) = &mut self.sea else {
            if surface.is_none() {
                self.waves = None;
                return Ok(());
            }
            return Err(MmusvError::input(
                "surface",
                "the scene has no sea surface; declare it with set_sea before setting a wave surface",
            ));
        };
        if surface.as_ref().is_some_and(|w| !w.is_finite()) {
            return Err(MmusvError::input(
                "surface",
                "the wave surface was sampled from a time, level, focus or wave component that is not finite; \
                 give finite values",
            ));
        }
        sea.set_wave_top(surface.as_ref().map(WaveSurface::zmax));
        self.waves = surface.map(Arc::new);
        Ok(())
    }

    /// The displaced sea surface of the current frame, if set (shared, cheap to clone).
    pub fn wave_surface(&self) -> Option<Arc<WaveSurface>> {
        self.waves.clone()
    }

    /// The instance the wave surface stands in for (left out of the tree walks), or `u32::MAX`.
    #[inline(always)]
    pub(super) fn hidden_instance(&self) -> u32 {
        match (&self.waves, &self.sea) {
            (Some(_), Some(sea)) => sea.instance,
            _ => u32::MAX,
        }
    }

    /// Whether hits on `instance` are wave-surface hits (their triangle index is a surface piece).
    #[inline(always)]
    pub(super) fn is_wave_hit(&self, instance: u32) -> bool {
        self.waves.is_some() && self.hidden_instance() == instance
    }

    /// Whether `ray` leaves the water ([`WaveSurface::leaves`]; false without a wave surface), read from the
    /// ray when its batch worked it out ([`RayPrep::leaves`]).
    #[inline(always)]
    pub(super) fn ray_leaves(&self, ray: &RayPrep) -> bool {
        ray.leaves_known().unwrap_or_else(|| self.waves.as_ref().is_some_and(|w| w.leaves(ray.o, ray.d)))
    }

    /// Works out [`RayPrep::leaves`] of `rays` once (with a wave surface; left unknown without one).
    #[inline(always)]
    pub(super) fn mark_leaves(&self, rays: &mut [RayPrep]) {
        let Some(w) = &self.waves else { return };
        // Rays from one point (a camera's pixels) share the height of the surface under it.
        let mut under: Option<([f32; 2], f32)> = None;
        for r in rays {
            if r.leaves == LEAVES_UNKNOWN {
                let h = |x: f32, y: f32| match under {
                    Some((p, h)) if p == [x, y] => h,
                    _ => {
                        let h = w.height(x, y);
                        under = Some(([x, y], h));
                        h
                    }
                };
                r.leaves = if w.leaves_over(r.o, r.d, h) { LEAVES_YES } else { LEAVES_NO };
            }
        }
    }

    /// The ray's hit with the wave surface below `limit`, as a hit on the sea instance.
    /// Rays leaving the water ([`WaveSurface::leaves`]) meet none.
    #[inline(always)]
    pub(super) fn wave_hit(&self, ray: &RayPrep, limit: f32) -> Option<Hit> {
        let w = self.waves.as_ref()?;
        if self.ray_leaves(ray) {
            return None;
        }
        let h = w.intersect(ray.o, ray.d, limit)?;
        Some(Hit { distance: h.t, instance: self.hidden_instance(), triangle: h.piece })
    }

    /// Intersects every ray of `p` with the wave surface below its `best`, shortening `best` where it hits; the
    /// sea instance and the piece per ray (`u32::MAX` where none), or `None` without a wave surface.
    #[inline(always)]
    pub(super) fn wave_hits_packet(&self, p: &mut Packet) -> Option<(u32, [u32; PACKET])> {
        self.known_wave_hits_packet(p, |_| WaterHit::Unknown)
    }

    /// [`Scene::wave_hit`] where the raster may already know the answer (`known`; [`WaterHit::Unknown`]
    /// marches).
    #[inline(always)]
    pub(super) fn known_wave_hit(&self, ray: &RayPrep, known: WaterHit, limit: f32) -> Option<Hit> {
        match known {
            WaterHit::Hit(h) if h.t < limit => {
                Some(Hit { distance: h.t, instance: self.hidden_instance(), triangle: h.piece })
            }
            WaterHit::Hit(_) | WaterHit::Miss => None,
            WaterHit::Unknown => self.wave_hit(ray, limit),
        }
    }

    /// [`Scene::wave_hits_packet`] where the raster may already know the answers (`known(r)` for ray `r`;
    /// [`WaterHit::Unknown`] marches).
    #[inline(always)]
    pub(super) fn known_wave_hits_packet(
        &self,
        p: &mut Packet,
        known: impl Fn(usize) -> WaterHit,
    ) -> Option<(u32, [u32; PACKET])> {
        let w = self.waves.as_ref()?;
        let mut pieces = [u32::MAX; PACKET];
        for r in 0..p.n {
            if p.best[r] < 0.0 {
                continue;
            }
            let hit = match known(r) {
                WaterHit::Hit(h) if h.t < p.best[r] => Some(h),
                WaterHit::Hit(_) | WaterHit::Miss => None,
                WaterHit::Unknown if self.ray_leaves(&p.ray[r]) => None,
                WaterHit::Unknown => w.intersect(p.ray[r].o, p.ray[r].d, p.best[r]),
            };
            if let Some(h) = hit {
                p.best[r] = h.t;
                pieces[r] = h.piece;
            }
        }
        Some((self.hidden_instance(), pieces))
    }

    /// Marks the rays of `p` the wave surface blocks below their `best` (`best = -1`).
    #[inline(always)]
    pub(super) fn wave_block_packet(&self, p: &mut Packet) {
        let Some(w) = &self.waves else { return };
        for r in 0..p.n {
            let ray = &p.ray[r];
            if p.best[r] >= 0.0 && !self.ray_leaves(ray) && w.occludes(ray.o, ray.d, p.best[r]) {
                p.best[r] = -1.0;
            }
        }
    }

    /// The unit normal of a wave-surface hit (`instance`, `triangle` as a hit reports them), `None` for any
    /// other hit.
    #[inline(always)]
    pub(super) fn wave_piece_normal(&self, instance: u32, triangle: u32) -> Option<Vec3> {
        if !self.is_wave_hit(instance) {
            return None;
        }
        Some(Vec3::from_array(self.waves.as_ref()?.piece_normal(triangle)))
    }
}
