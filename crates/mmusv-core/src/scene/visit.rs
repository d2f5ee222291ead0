//! The top-level leaf visitors of a [`Scene`]'s traversals: at each leaf of the instance BVH, the instances
//! whose boxes the ray (or packet) enters, cheapest first, each traced in its own frame.

use super::{Scene, Scratch};
use crate::bvh::{box_entry, Packet, PacketStack, PacketVisit, Stack, Visit, PACKET};
use crate::geometry::RigidPose;
use crate::ray::RayPrep;
use crate::simd::Level;
use parry3d::math::Vec3;

/// The top-level leaf visitor of [`Scene::cast_ray_with`]: each instance's mesh, cheapest first, in its local
/// frame (instances at the identity pose use the world ray as it is).
pub(super) struct Instances<'a, L> {
    pub(super) lv: L,
    pub(super) scene: &'a Scene,
    pub(super) ray: &'a RayPrep,
    pub(super) stack: &'a mut Stack,
    pub(super) instance: u32,
    pub(super) triangle: u32,
    /// An instance left out (the flat sea mesh while the wave surface stands in for it), or `u32::MAX`.
    pub(super) hidden: u32,
}

impl<L: Level> Visit for Instances<'_, L> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, mut best: f32) -> f32 {
        let sc = self.scene;
        let lf = sc.tlas.leaves()[leaf as usize];
        for k in lf.start as usize..(lf.start + lf.count) as usize {
            let id = sc.tlas_order[k];
            if id == self.hidden || !box_entry(&sc.tlas_boxes[k], self.ray, best) {
                continue;
            }
            let inst = &sc.instances[id as usize];
            let mesh = &sc.meshes[inst.mesh as usize];
            let local = local_ray(self.ray, &inst.pose);
            if let Some(h) = mesh.closest(self.lv, local.as_ref().unwrap_or(self.ray), best, self.stack) {
                best = h.t;
                self.instance = id;
                self.triangle = h.triangle;
            }
        }
        best
    }
}

/// The top-level leaf visitor of [`Scene::occluded_with`].
pub(super) struct AnyInstance<'a, L> {
    pub(super) lv: L,
    pub(super) scene: &'a Scene,
    pub(super) ray: &'a RayPrep,
    pub(super) stack: &'a mut Stack,
    pub(super) hidden: u32,
}

impl<L: Level> Visit for AnyInstance<'_, L> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, best: f32) -> f32 {
        let sc = self.scene;
        let lf = sc.tlas.leaves()[leaf as usize];
        for k in lf.start as usize..(lf.start + lf.count) as usize {
            let id = sc.tlas_order[k];
            if id == self.hidden || !box_entry(&sc.tlas_boxes[k], self.ray, best) {
                continue;
            }
            let inst = &sc.instances[id as usize];
            let local = local_ray(self.ray, &inst.pose);
            if sc.meshes[inst.mesh as usize].any(self.lv, local.as_ref().unwrap_or(self.ray), best, self.stack) {
                return 0.0;
            }
        }
        best
    }
}

/// The ray in an instance's local frame, or `None` when the pose is the identity (the world ray then serves).
#[inline(always)]
pub(super) fn local_ray(ray: &RayPrep, pose: &RigidPose) -> Option<RayPrep> {
    if *pose == RigidPose::IDENTITY {
        return None;
    }
    let rt = pose.rotation.transpose();
    let o = rt * (Vec3::from_array(ray.o) - pose.translation);
    let d = rt * Vec3::from_array(ray.d);
    Some(RayPrep::new(o.to_array(), d.to_array()))
}

/// The top-level leaf visitor of packets: each instance whose box some ray enters, cheapest first; its mesh
/// is traced with the rays that enter its box, as a packet in the instance's frame where their directions
/// still share signs there, else ray by ray.
pub(super) struct PacketInstances<'a, L> {
    pub(super) lv: L,
    pub(super) scene: &'a Scene,
    pub(super) scratch_single: &'a mut Stack,
    pub(super) stack: &'a mut PacketStack,
    /// The packet of a moved instance's rays in its frame (filled anew for each such instance).
    pub(super) sub: &'a mut Packet,
    pub(super) instance: [u32; PACKET],
    pub(super) triangle: [u32; PACKET],
    pub(super) any: bool,
    pub(super) hidden: u32,
}

impl<'a, L: Level> PacketInstances<'a, L> {
    /// The visitor of `scene`'s packets at level `lv`, on `scratch`'s stacks and with no hit yet; `any`: occlusion
    /// (each ray stops at its first hit), else the closest hits. Also hands back `scratch`'s top-level packet stack,
    /// for the walk of the instance BVH that this visitor serves.
    #[inline(always)]
    pub(super) fn new(lv: L, scene: &'a Scene, scratch: &'a mut Scratch, any: bool) -> (Self, &'a mut PacketStack) {
        let Scratch { bottom, packet_top, packet_bottom, sub_packet, .. } = scratch;
        let visitor = Self {
            lv,
            scene,
            scratch_single: bottom,
            stack: packet_bottom,
            sub: sub_packet,
            instance: [u32::MAX; PACKET],
            triangle: [u32::MAX; PACKET],
            any,
            hidden: scene.hidden_instance(),
        };
        (visitor, packet_top)
    }
}

impl<L: Level> PacketVisit for PacketInstances<'_, L> {
    #[inline(always)]
    fn leaf(&mut self, leaf: u32, rays: u32, p: &mut Packet) {
        let sc = self.scene;
        let lf = sc.tlas.leaves()[leaf as usize];
        for k in lf.start as usize..(lf.start + lf.count) as usize {
            let id = sc.tlas_order[k];
            if id == self.hidden {
                continue;
            }
            let mask = p.rays_entering_box(&sc.tlas_boxes[k]) & rays;
            if mask == 0 {
                continue;
            }
            let inst = &sc.instances[id as usize];
            let mesh = &sc.meshes[inst.mesh as usize];
            if inst.pose == RigidPose::IDENTITY {
                // Trace the world packet, with the rays outside `mask` switched off for this instance.
                let saved = p.best;
                for r in 0..PACKET {
                    if mask & (1 << r) == 0 {
                        p.best[r] = -1.0;
                    }
                }
                let mut tri = [u32::MAX; PACKET];
                if self.any {
                    mesh.any_packet(self.lv, p, self.stack);
                } else {
                    mesh.closest_packet(self.lv, p, self.stack, &mut tri);
                }
                for r in 0..PACKET {
                    if mask & (1 << r) == 0 {
                        p.best[r] = saved[r];
                    } else if !self.any && p.best[r] < saved[r] {
                        self.instance[r] = id;
                        self.triangle[r] = tri[r];
                    }
                }
                continue;
            }
            // Moved instance: the rays in its frame.
            let mut local = [p.ray[0]; PACKET];
            let mut lane = [0usize; PACKET];
            let mut n = 0;
            let mut m = mask;
            while m != 0 {
                let r = m.trailing_zeros() as usize;
                m &= m - 1;
                local[n] = local_ray(&p.ray[r], &inst.pose).unwrap_or(p.ray[r]);
                lane[n] = r;
                n += 1;
            }
            let q = &mut *self.sub;
            if n > 1 && q.fill(&local[..n], 0.0) {
                for j in 0..n {
                    q.best[j] = p.best[lane[j]];
                }
                let mut tri = [u32::MAX; PACKET];
                if self.any {
                    mesh.any_packet(self.lv, q, self.stack);
                } else {
                    mesh.closest_packet(self.lv, q, self.stack, &mut tri);
                }
                for j in 0..n {
                    let r = lane[j];
                    if q.best[j] < p.best[r] {
                        p.best[r] = q.best[j];
                        self.instance[r] = id;
                        self.triangle[r] = tri[j];
                    }
                }
            } else {
                for j in 0..n {
                    let r = lane[j];
                    if self.any {
                        if mesh.any(self.lv, &local[j], p.best[r], self.scratch_single) {
                            p.best[r] = -1.0;
                        }
                    } else if let Some(h) = mesh.closest(self.lv, &local[j], p.best[r], self.scratch_single) {
                        p.best[r] = h.t;
                        self.instance[r] = id;
                        self.triangle[r] = h.triangle;
                    }
                }
            }
        }
    }
}
