//! The sea shortcuts of a [`Scene`] (see [`crate::sea`]): declaring the sea surface, and the routes that
//! settle a ray without the full trace (down onto the surface, up into the sky, towards the sun).

use super::{coherent, local_ray, Hit, Scene, Scratch};
use crate::bvh::{Box3, Packet, PACKET};
use crate::error::{MmusvError, Result};
use crate::ray::RayPrep;
use crate::sea::{Horizon, Sea, SunMask};
use crate::simd::Level;

/// Longest height-map walks (cells) worth trying before a full trace: down to the sea, up into the sky (camera
/// rays), up towards the sun (shadow rays).
const SEA_WALK_DOWN: usize = 12;
const SEA_WALK_SKY: usize = 2;
const SEA_WALK_SHADOW: usize = 2;

/// How the sea shortcut settles a closest-hit query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SeaRoute {
    /// Down onto the surface with nothing in between: test the surface mesh alone.
    Surface,
    /// Up and clear of everything: a miss.
    Sky,
    /// Anything else: the full trace.
    Trace,
}

impl Scene {
    /// Declares instance `surface` the sea surface, so rays that can only meet it or the sky are answered
    /// without a full trace (see [`crate::sea`]); `moving` lists the instances that will move (vessels): the
    /// height bound takes their boxes after every move, and everything else triangle by triangle. Answers stay
    /// exactly those of the full trace.
    ///
    /// The surface's world triangles must all lie at one height (a horizontal plane), else an input error.
    pub fn set_sea(&mut self, surface: u32, moving: &[u32]) -> Result<()> {
        self.check_instance(surface)?;
        for &id in moving {
            self.check_instance(id)?;
        }
        let inst = &self.instances[surface as usize];
        let mesh = &self.meshes[inst.mesh as usize];
        let level = inst.pose.transform_point(mesh.vertices()[0]).z;
        if mesh.vertices().iter().any(|&v| inst.pose.transform_point(v).z != level) {
            return Err(MmusvError::input(
                "surface",
                format!("instance {surface} is not a horizontal plane; the sea surface must be flat and level"),
            ));
        }
        let mut bounds = Box3::EMPTY;
        let mut fixed = Vec::new();
        for (id, inst) in self.instances.iter().enumerate() {
            let id = id as u32;
            if id == surface {
                continue;
            }
            let a = &self.world_aabbs[id as usize];
            bounds.grow(&Box3 { lo: a.mins.to_array(), hi: a.maxs.to_array() });
            if !moving.contains(&id) {
                let mesh = &self.meshes[inst.mesh as usize];
                fixed.extend(
                    mesh.faces().iter().map(|f| f.map(|k| inst.pose.transform_point(mesh.vertices()[k as usize]))),
                );
            }
        }
        let mut sea = Sea::new(surface, level, bounds, moving.to_vec(), &fixed);
        let boxes = &self.world_aabbs;
        sea.update(
            moving
                .iter()
                .map(|&i| Box3 { lo: boxes[i as usize].mins.to_array(), hi: boxes[i as usize].maxs.to_array() }),
        );
        self.sea = Some(sea);
        Ok(())
    }

    /// Forgets the sea surface: every ray is traced fully again.
    pub fn clear_sea(&mut self) {
        self.sea = None;
    }

    /// The declared sea surface instance, if any.
    pub fn sea_instance(&self) -> Option<u32> {
        self.sea.as_ref().map(|s| s.instance)
    }

    /// The sea shortcut for a closest-hit query: `Some(Some(hit))` when the ray goes down from above the surface
    /// and nothing can be hit before it (the hit is the surface's, found by testing its mesh alone), `Some(None)`
    /// when the ray rises clear above everything (a miss), `None` when the ray needs the full trace.
    #[inline(always)]
    pub fn sea_closest<L: Level>(
        &self,
        lv: L,
        ray: &RayPrep,
        limit: f32,
        scratch: &mut Scratch,
    ) -> Option<Option<Hit>> {
        match self.sea_route(ray, limit, None) {
            SeaRoute::Sky => Some(None),
            SeaRoute::Trace => None,
            SeaRoute::Surface => self.sea_surface_hit(lv, ray, limit, scratch).map(Some),
        }
    }

    /// Which way the sea shortcut settles a closest-hit query (see [`Scene::sea_closest`]); `horizon`, when
    /// given, is the [`Horizon`] of the ray's origin.
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a < b)` on purpose: a NaN must take the full trace
    pub(super) fn sea_route(&self, ray: &RayPrep, limit: f32, horizon: Option<&Horizon>) -> SeaRoute {
        let Some(sea) = self.sea.as_ref() else { return SeaRoute::Trace };
        let (oz, dz) = (ray.o[2], ray.d[2]);
        if !(oz > sea.level) {
            return SeaRoute::Trace;
        }
        if dz < 0.0 {
            let t_w = (sea.level - oz) / dz;
            let clear = t_w < limit
                && match horizon {
                    // From a viewpoint over a vessel (a USV's camera): clear of its triangles, then of the rest.
                    Some(h) => h.clear_of_near(ray.d) && sea.path_clear_from(h, ray.o, ray.d, t_w, SEA_WALK_DOWN),
                    None => sea.path_clear(ray.o, ray.d, t_w, SEA_WALK_DOWN),
                };
            return if clear { SeaRoute::Surface } else { SeaRoute::Trace };
        }
        if let Some(h) = horizon {
            debug_assert_eq!(h.origin(), ray.o, "a horizon answers only for rays from its viewpoint");
            if h.clear(ray.d) {
                return SeaRoute::Sky;
            }
        }
        if self.sea_clear_within(ray, limit, SEA_WALK_SKY) {
            SeaRoute::Sky
        } else {
            SeaRoute::Trace
        }
    }

    /// The [`Horizon`] of viewpoint `origin` (see [`crate::sea`]): the static height map, the moving instances'
    /// boxes, and the triangles of those whose boxes stand over it. `None` when the sea shortcuts do not apply.
    pub(super) fn horizon(&self, origin: [f32; 3]) -> Option<Horizon> {
        let (mut h, near) = self.sea.as_ref()?.horizon(origin)?;
        for id in near {
            let inst = &self.instances[id as usize];
            let mesh = &self.meshes[inst.mesh as usize];
            for f in mesh.faces() {
                h.add_triangle(f.map(|k| inst.pose.transform_point(mesh.vertices()[k as usize]).to_array()));
            }
        }
        Some(h)
    }

    /// The closest hit of a ray [`Scene::sea_route`] sent to the surface, from the surface mesh alone (`None`
    /// when it misses the mesh: the ray then needs the full trace).
    #[inline(always)]
    fn sea_surface_hit<L: Level>(&self, lv: L, ray: &RayPrep, limit: f32, scratch: &mut Scratch) -> Option<Hit> {
        let sea = self.sea.as_ref()?;
        let inst = &self.instances[sea.instance as usize];
        let local = local_ray(ray, &inst.pose);
        let mesh = &self.meshes[inst.mesh as usize];
        let h = mesh.closest(lv, local.as_ref().unwrap_or(ray), limit, &mut scratch.bottom)?;
        Some(Hit { distance: h.t, instance: sea.instance, triangle: h.triangle })
    }

    /// [`Scene::sea_surface_hit`] for up to [`PACKET`] rays at once, traced as one packet against the surface
    /// mesh when they are coherent (each ray gets the hit it gets alone).
    #[inline(always)]
    pub(super) fn sea_surface_hits<L: Level>(
        &self,
        lv: L,
        rays: &[RayPrep],
        limit: f32,
        scratch: &mut Scratch,
    ) -> [Option<Hit>; PACKET] {
        let mut out = [None; PACKET];
        let Some(sea) = self.sea.as_ref() else { return out };
        let inst = &self.instances[sea.instance as usize];
        let mesh = &self.meshes[inst.mesh as usize];
        let mut local = [rays[0]; PACKET];
        for (j, ray) in rays.iter().enumerate() {
            local[j] = local_ray(ray, &inst.pose).unwrap_or(*ray);
        }
        let local = &local[..rays.len()];
        let packet = if coherent(local) { Packet::new(local, limit) } else { None };
        if let Some(mut p) = packet {
            let mut tri = [u32::MAX; PACKET];
            mesh.closest_packet(lv, &mut p, &mut scratch.packet_bottom, &mut tri);
            for j in 0..rays.len() {
                if tri[j] != u32::MAX {
                    out[j] = Some(Hit { distance: p.best[j], instance: sea.instance, triangle: tri[j] });
                }
            }
        } else {
            for (j, ray) in rays.iter().enumerate() {
                out[j] = self.sea_surface_hit(lv, ray, limit, scratch);
            }
        }
        out
    }

    /// The sea shortcut for an any-hit query: whether the ray rises from above the surface and stays clear of
    /// everything (then nothing is hit below `limit`).
    #[inline(always)]
    pub fn sea_clear(&self, ray: &RayPrep, limit: f32) -> bool {
        self.sea_clear_within(ray, limit, SEA_WALK_SHADOW)
    }

    /// The sun-mask shortcut for an any-hit query: whether `ray` (with the direction `mask` was built for)
    /// starts above the surface in a cell no occluder can shade.
    #[inline(always)]
    pub(super) fn sun_clear(&self, mask: Option<&SunMask>, ray: &RayPrep) -> bool {
        match (&self.sea, mask) {
            (Some(sea), Some(mask)) => sea.sun_clear(mask, ray.o),
            _ => false,
        }
    }

    #[inline(always)]
    fn sea_clear_within(&self, ray: &RayPrep, limit: f32, max_cells: usize) -> bool {
        let Some(sea) = &self.sea else { return false };
        let (oz, dz) = (ray.o[2], ray.d[2]);
        if !(oz > sea.level && dz > 0.0) {
            return false;
        }
        if oz > sea.top() {
            return true;
        }
        let t_top = (sea.top() - oz) / dz;
        sea.path_clear(ray.o, ray.d, t_top.min(limit), max_cells)
    }
}
