//! The sea shortcuts of a [`Scene`] (see [`crate::sea`]): declaring the sea surface, and the routes that
//! settle a ray without the full trace (up into the sky, towards the sun).

use super::Scene;
use crate::bvh::Box3;
use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::ray::RayPrep;
use crate::sea::{Horizon, Sea, SunMask};

/// Longest height-map walks (cells) worth trying before a full trace: up into the sky (camera rays, which ask
/// their viewpoint's horizon first), up into the sky from many origins (no horizon: rays reflected by the
/// water, each of which would otherwise be traced in full), up towards the sun (shadow rays).
const SEA_WALK_SKY: usize = 2;
const SEA_WALK_SKY_NO_HORIZON: usize = 48;
const SEA_WALK_SHADOW: usize = 2;
/// Longest walk (cells) over the height map for the stretch of a rising ray among the waves.
const SEA_WALK_LIFT: usize = 8;
/// Room (m) the height grid leaves round the scene's instances in x and y, so that a moving instance at the edge
/// of everything else stays inside it as it sways: a map's last buoy tilting with the waves (a 3.8 m buoy at 10°
/// moves its box 0.7 m) left the grid, and a moving box outside it turns every viewpoint's horizon off
/// ([`Sea::horizon`]): `port_entry`'s cameras took 7 % more CPU. The tallest hull rolling 5° moves its top 5 m.
const SWAY_M: f32 = 10.0;

/// A sea surface built from one state of a scene by [`Scene::prepare_sea`], to be installed by
/// [`Scene::install_sea`].
#[derive(Debug, Clone)]
pub struct PreparedSea {
    surface: u32,
    moving: Vec<u32>,
    sea: Sea,
    /// Mesh and pose of every instance when the grid was built (by instance id).
    placed: Vec<(u32, RigidPose)>,
}

impl Scene {
    /// Declares instance `surface` the sea surface, so rays that can only meet it or the sky are answered
    /// without a full trace (see [`crate::sea`]); `moving` lists the instances that will move (vessels): the
    /// height bound takes their boxes after every move, and everything else triangle by triangle. Answers stay
    /// exactly those of the full trace.
    ///
    /// The surface's world triangles must all lie at one height (a horizontal plane), else an input error.
    pub fn set_sea(&mut self, surface: u32, moving: &[u32]) -> Result<()> {
        let prepared = self.prepare_sea(surface, moving)?;
        self.install_sea(prepared)
    }

    /// The costly half of [`Scene::set_sea`]: builds the height grid of this state of the scene without
    /// changing it, so that a caller can build on a snapshot outside its lock and install the result under it
    /// ([`Scene::install_sea`]). Errors as [`Scene::set_sea`].
    pub fn prepare_sea(&self, surface: u32, moving: &[u32]) -> Result<PreparedSea> {
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
        for axis in 0..2 {
            bounds.lo[axis] -= SWAY_M;
            bounds.hi[axis] += SWAY_M;
        }
        Ok(PreparedSea {
            surface,
            moving: moving.to_vec(),
            sea: Sea::new(surface, level, bounds, moving.to_vec(), &fixed),
            placed: self.instances.iter().map(|i| (i.mesh, i.pose)).collect(),
        })
    }

    /// Installs a sea built by [`Scene::prepare_sea`], possibly on an earlier state of this scene: the moving
    /// instances' boxes are taken as they are now, and a grid whose fixed geometry has changed since (an
    /// instance added, or one not declared moving placed anew) is built again here. So a `set_poses` made while
    /// the grid was built elsewhere is kept and counted.
    pub fn install_sea(&mut self, prepared: PreparedSea) -> Result<()> {
        let stale = prepared.placed.len() != self.instances.len()
            || self.instances.iter().zip(&prepared.placed).enumerate().any(|(id, (inst, &(mesh, pose)))| {
                !prepared.moving.contains(&(id as u32)) && (inst.mesh != mesh || inst.pose != pose)
            });
        let PreparedSea { moving, mut sea, .. } =
            if stale { self.prepare_sea(prepared.surface, &prepared.moving)? } else { prepared };
        let boxes = &self.world_aabbs;
        sea.update(
            moving
                .iter()
                .map(|&i| Box3 { lo: boxes[i as usize].mins.to_array(), hi: boxes[i as usize].maxs.to_array() }),
        );
        self.sea = Some(sea);
        self.waves = None;
        Ok(())
    }

    /// Forgets the sea surface: every ray is traced fully again.
    pub fn clear_sea(&mut self) {
        self.sea = None;
        self.waves = None;
    }

    /// The declared sea surface instance, if any.
    pub fn sea_instance(&self) -> Option<u32> {
        self.sea.as_ref().map(|s| s.instance)
    }

    /// The still water beyond every ray's range ([`SeaBeyond`]), when the scene has a sea.
    /// A camera labels a pixel that meets it water, as its shading draws it ([`crate::sensors::camera::Camera`]),
    /// not sky.
    pub fn sea_beyond(&self) -> Option<SeaBeyond> {
        let sea = self.sea.as_ref()?;
        Some(SeaBeyond { instance: sea.instance as i32, class: self.face_class(sea.instance, 0), level: sea.level })
    }

    /// The sea shortcut for a closest-hit query: whether the ray rises from above the surface clear of
    /// everything (then it hits nothing: a miss, exactly as the full trace finds). `horizon`, when given, is the
    /// [`Horizon`] of the ray's origin. A ray going down is always traced: the full trace finds the surface as
    /// fast as a walk over the height map could rule out everything above it.
    #[inline(always)]
    pub fn sea_sky(&self, ray: &RayPrep, limit: f32, horizon: Option<&Horizon>) -> bool {
        if let Some(h) = horizon {
            debug_assert_eq!(h.origin(), ray.o, "a horizon answers only for rays from its viewpoint");
            if h.clear(ray.d) {
                return true;
            }
            return self.sea_clear_within(ray, limit, SEA_WALK_SKY);
        }
        self.sea_clear_within(ray, limit, SEA_WALK_SKY_NO_HORIZON)
    }

    /// The [`Horizon`] of viewpoint `origin` (see [`crate::sea`]): the static height map, the moving instances'
    /// boxes, the triangles of those whose boxes stand over it, and, from among the waves, their crests
    /// ([`crate::sea::WaveSurface::add_crests`]). `None` when the sea shortcuts do not apply.
    pub(super) fn horizon(&self, origin: [f32; 3]) -> Option<Horizon> {
        let (mut h, near) = self.sea.as_ref()?.horizon(origin)?;
        for id in near {
            let inst = &self.instances[id as usize];
            let mesh = &self.meshes[inst.mesh as usize];
            // Each vertex moved into the world once, not once per face that holds it.
            let world: Vec<[f32; 3]> =
                mesh.vertices().iter().map(|&v| inst.pose.transform_point(v).to_array()).collect();
            h.add_mesh(&world, mesh.faces());
        }
        // A viewpoint among the waves (not over their crest bound; finite, as `Sea::horizon` checked): the crests
        // are columns too.
        if let (Some(w), Some(sea)) = (&self.waves, &self.sea) {
            if origin[2] <= sea.surface_top() {
                w.add_crests(&mut h);
            }
        }
        Some(h)
    }

    /// The sea shortcut for an any-hit query: whether the ray rises from above the surface and stays clear of
    /// everything (then nothing is hit below `limit`).
    #[inline(always)]
    pub fn sea_clear(&self, ray: &RayPrep, limit: f32) -> bool {
        self.sea_clear_within(ray, limit, SEA_WALK_SHADOW)
    }

    /// The sun-mask shortcut for an any-hit query: whether a ray from `origin` (with the direction `mask` was
    /// built for) starts above the surface in a cell no occluder can shade. `false` for a non-finite origin.
    #[inline(always)]
    pub(super) fn sun_clear(&self, mask: Option<&SunMask>, origin: [f32; 3]) -> bool {
        match (&self.sea, mask) {
            (Some(sea), Some(mask)) => {
                if !origin.iter().all(|v| v.is_finite()) {
                    return false;
                }
                match self.lift_over_waves(sea, origin, mask.dir(), f32::MAX, None) {
                    Lift::Above(o) => sea.sun_clear(mask, o),
                    Lift::Beyond | Lift::Unknown => false,
                }
            }
            _ => false,
        }
    }

    /// A rising ray that starts among the waves (below their crest bound), carried up to just over the bound
    /// when nothing meets it on the way: the wave surface (exactly; none for a ray leaving the water,
    /// [`crate::sea::WaveSurface::leaves`], which only needs to clear the still level) and every other surface
    /// (the height map walk over at most [`SEA_WALK_LIFT`] cells). Without waves, or from above the bound, the
    /// origin as it is. `leaves`: [`crate::sea::WaveSurface::leaves`] of the ray when already known.
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "not known"
    fn lift_over_waves(
        &self,
        sea: &crate::sea::Sea,
        o: [f32; 3],
        d: [f32; 3],
        limit: f32,
        leaves: Option<bool>,
    ) -> Lift {
        let mut top = sea.surface_top();
        if o[2] > top {
            return Lift::Above(o);
        }
        let Some(w) = &self.waves else { return Lift::Unknown };
        if !(d[2] > 0.0) {
            return Lift::Unknown;
        }
        let leaves = leaves.unwrap_or_else(|| w.leaves(o, d));
        if leaves {
            top = sea.level;
            if o[2] > top {
                return Lift::Above(o);
            }
        }
        let t = ((top - o[2]) / d[2]) * 1.0001 + 1e-3 / d[2];
        if (!leaves && w.occludes(o, d, t.min(limit))) || !sea.path_clear(o, d, t.min(limit), SEA_WALK_LIFT) {
            return Lift::Unknown;
        }
        if t >= limit {
            return Lift::Beyond;
        }
        let lifted = [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t];
        if lifted[2] > top {
            Lift::Above(lifted)
        } else {
            Lift::Unknown
        }
    }

    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "not clear"
    fn sea_clear_within(&self, ray: &RayPrep, limit: f32, max_cells: usize) -> bool {
        let Some(sea) = &self.sea else { return false };
        if !(ray.d[2] > 0.0) {
            return false;
        }
        let (o, limit) = match self.lift_over_waves(sea, ray.o, ray.d, limit, ray.leaves_known()) {
            Lift::Above(o) if o == ray.o => (o, limit),
            Lift::Above(o) => {
                let t = (o[2] - ray.o[2]) / ray.d[2];
                (o, limit - t)
            }
            Lift::Beyond => return true,
            Lift::Unknown => return false,
        };
        let (oz, dz) = (o[2], ray.d[2]);
        if !(oz > sea.level) {
            return false;
        }
        if oz > sea.top() {
            return true;
        }
        let t_top = (sea.top() - oz) / dz;
        sea.path_clear(o, ray.d, t_top.min(limit), max_cells)
    }
}

/// Where a rising ray stands against the waves ([`Scene::lift_over_waves`]).
enum Lift {
    /// It is (or, nothing met on the way, continues as the ray from) this point above the crest bound.
    Above([f32; 3]),
    /// Nothing is met before its end.
    Beyond,
    /// Not known: trace it.
    Unknown,
}

/// What a ray that met nothing within its range would meet beyond it, where that is the sea ([`Scene::sea_beyond`]):
/// the sea instance's id and semantic class, and the still water's level.
#[derive(Debug, Clone, Copy)]
pub struct SeaBeyond {
    /// Instance id of the sea surface.
    pub instance: i32,
    /// Its semantic class.
    pub class: u16,
    level: f32,
}

impl SeaBeyond {
    /// The distance along the ray from `origin` along unit `dir` to the still water, when the ray starts above it and
    /// goes down (it meets the water somewhere, past the range or past the water's mesh); `None` otherwise, and where
    /// that distance overflows.
    #[inline]
    pub fn meet(&self, origin: [f32; 3], dir: [f32; 3]) -> Option<f32> {
        if !(origin[2] > self.level && dir[2] < 0.0) {
            return None;
        }
        let t = (origin[2] - self.level) / -dir[2];
        t.is_finite().then_some(t)
    }
}
