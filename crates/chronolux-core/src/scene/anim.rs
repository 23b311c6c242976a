//! Animation evaluation at any time `t`: keyframe channels (STEP, LINEAR with slerp for
//! rotations, CUBICSPLINE), the resulting node pose, and per-frame vertex deformation by
//! morph targets and linear blend skinning (on the CPU). Which time a frame shows is
//! [`frame_time`](super::source::frame_time)'s business.

use super::desc::{
    AnimationId, Channel, ChannelTarget, Interpolation, NodeId, Primitive, SceneDesc, Trs,
};
use crate::math::{Mat3, Mat4, Quat, Vec3, Vec4};

/// Evaluates one channel at time `t` (seconds); returns `channel.components` values.
/// Before the first key the first value holds, after the last key the last (glTF rule).
pub fn evaluate_channel(ch: &Channel, t: f32) -> Vec<f32> {
    let n = ch.components;
    let keys = ch.times.len();
    let stride = if ch.interpolation == Interpolation::CubicSpline {
        3 * n
    } else {
        n
    };
    // Offset of the value (not tangents) of key k.
    let value_at = |k: usize| -> &[f32] {
        let base = k * stride
            + if ch.interpolation == Interpolation::CubicSpline {
                n
            } else {
                0
            };
        &ch.values[base..base + n]
    };
    if keys == 0 {
        return vec![0.0; n];
    }
    if keys == 1 || t <= ch.times[0] {
        return value_at(0).to_vec();
    }
    if t >= ch.times[keys - 1] {
        return value_at(keys - 1).to_vec();
    }
    // k: last key with times[k] <= t; t < times[k+1].
    let k = ch.times.partition_point(|&x| x <= t) - 1;
    let (t0, t1) = (ch.times[k], ch.times[k + 1]);
    let dt = t1 - t0;
    let s = if dt > 0.0 { (t - t0) / dt } else { 0.0 };
    let is_rotation = ch.target == ChannelTarget::Rotation;
    match ch.interpolation {
        Interpolation::Step => value_at(k).to_vec(),
        Interpolation::Linear => {
            let (a, b) = (value_at(k), value_at(k + 1));
            if is_rotation {
                let qa = Quat::from_xyzw(a[0], a[1], a[2], a[3]).normalize();
                let qb = Quat::from_xyzw(b[0], b[1], b[2], b[3]).normalize();
                let q = slerp_shortest(qa, qb, s);
                vec![q.x, q.y, q.z, q.w]
            } else {
                a.iter().zip(b).map(|(x, y)| x + (y - x) * s).collect()
            }
        }
        Interpolation::CubicSpline => {
            let v0 = value_at(k);
            let v1 = value_at(k + 1);
            let out0 = &ch.values[k * stride + 2 * n..k * stride + 3 * n];
            let in1 = &ch.values[(k + 1) * stride..(k + 1) * stride + n];
            let (s2, s3) = (s * s, s * s * s);
            let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
            let h10 = s3 - 2.0 * s2 + s;
            let h01 = -2.0 * s3 + 3.0 * s2;
            let h11 = s3 - s2;
            let mut v: Vec<f32> = (0..n)
                .map(|i| h00 * v0[i] + h10 * dt * out0[i] + h01 * v1[i] + h11 * dt * in1[i])
                .collect();
            if is_rotation {
                let q = Quat::from_xyzw(v[0], v[1], v[2], v[3]).normalize();
                v = vec![q.x, q.y, q.z, q.w];
            }
            v
        }
    }
}

/// Spherical interpolation along the shorter arc.
pub fn slerp_shortest(a: Quat, b: Quat, s: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    a.slerp(b, s).normalize()
}

/// The state of every node at one time.
#[derive(Clone, Debug)]
pub struct Pose {
    /// Local transform per node.
    pub local: Vec<Trs>,
    /// `world_from_node` per node.
    pub world: Vec<Mat4>,
    /// Morph weights per node (the node's mesh's weights, animated); empty when the node's
    /// mesh has no targets.
    pub weights: Vec<Vec<f32>>,
}

/// Evaluates the pose of every node at time `t` under clip `anim` (`None`: rest pose).
pub fn pose_at(desc: &SceneDesc, anim: Option<AnimationId>, t: f32) -> Pose {
    let mut local: Vec<Trs> = desc.nodes.iter().map(|n| n.transform).collect();
    let mut weights: Vec<Vec<f32>> = desc
        .nodes
        .iter()
        .map(|n| match n.mesh {
            Some(_) if !n.weights.is_empty() => n.weights.clone(),
            Some(m) => desc.meshes[m.index()].weights.clone(),
            None => n.weights.clone(),
        })
        .collect();
    if let Some(a) = anim {
        for ch in &desc.animations[a.index()].channels {
            let v = evaluate_channel(ch, t);
            let i = ch.node.index();
            match ch.target {
                ChannelTarget::Translation => local[i].translation = Vec3::new(v[0], v[1], v[2]),
                ChannelTarget::Scale => local[i].scale = Vec3::new(v[0], v[1], v[2]),
                ChannelTarget::Rotation => {
                    local[i].rotation = Quat::from_xyzw(v[0], v[1], v[2], v[3]).normalize()
                }
                ChannelTarget::Weights => weights[i] = v,
            }
        }
    }
    let mut world = vec![Mat4::IDENTITY; desc.nodes.len()];
    for id in desc.topological_order() {
        let i = id.index();
        let m = local[i].matrix();
        world[i] = match desc.nodes[i].parent {
            Some(p) => world[p.index()] * m,
            None => m,
        };
    }
    Pose {
        local,
        world,
        weights,
    }
}

/// Which nodes change under clip `anim`: those with a channel, their descendants, and mesh
/// nodes skinned by a changing joint. Derived from the animation, never from pixels.
pub fn dynamic_nodes(desc: &SceneDesc, anim: Option<AnimationId>) -> Vec<bool> {
    let mut dynamic = vec![false; desc.nodes.len()];
    let mut morph = vec![false; desc.nodes.len()];
    if let Some(a) = anim {
        for ch in &desc.animations[a.index()].channels {
            let changes = ch.values.windows(2).any(|w| w[0] != w[1]) && ch.times.len() > 1;
            if !changes {
                continue;
            }
            if ch.target == ChannelTarget::Weights {
                morph[ch.node.index()] = true;
            } else {
                dynamic[ch.node.index()] = true;
            }
        }
    }
    for id in desc.topological_order() {
        if let Some(p) = desc.nodes[id.index()].parent
            && dynamic[p.index()]
        {
            dynamic[id.index()] = true;
        }
    }
    let mut out = dynamic.clone();
    for (i, n) in desc.nodes.iter().enumerate() {
        if morph[i] {
            out[i] = true;
        }
        if let Some(s) = n.skin
            && desc.skins[s.index()]
                .joints
                .iter()
                .any(|j| dynamic[j.index()])
        {
            out[i] = true;
        }
    }
    out
}

/// Vertex positions and normals of `prim` (a primitive of `node`'s mesh) at `pose`, in
/// **world space** when the node is skinned and in **object space** otherwise (then the
/// caller applies `pose.world[node]`). Returns `None` when the primitive is neither morphed
/// nor skinned (the caller uses the rest attributes).
pub fn deform_primitive(
    desc: &SceneDesc,
    node: NodeId,
    prim: &Primitive,
    pose: &Pose,
) -> Option<(Vec<Vec3>, Option<Vec<Vec3>>)> {
    let n = &desc.nodes[node.index()];
    let weights = &pose.weights[node.index()];
    let morphed = !prim.morph_targets.is_empty() && weights.iter().any(|&w| w != 0.0);
    let skin = n
        .skin
        .filter(|_| prim.joints.is_some() && prim.joint_weights.is_some());
    if !morphed && skin.is_none() {
        return None;
    }
    let mut pos = prim.positions.clone();
    let mut nrm = prim.normals.clone();
    if morphed {
        for (target, &w) in prim.morph_targets.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            if let Some(dp) = &target.positions {
                for (p, d) in pos.iter_mut().zip(dp) {
                    *p += w * *d;
                }
            }
            if let (Some(nn), Some(dn)) = (nrm.as_mut(), &target.normals) {
                for (p, d) in nn.iter_mut().zip(dn) {
                    *p += w * *d;
                }
            }
        }
    }
    if let Some(s) = skin {
        let skin = &desc.skins[s.index()];
        let joint_mats: Vec<Mat4> = skin
            .joints
            .iter()
            .zip(&skin.inverse_bind_matrices)
            .map(|(j, ibm)| pose.world[j.index()] * *ibm)
            .collect();
        let joints = prim.joints.as_ref().unwrap();
        let jw = prim.joint_weights.as_ref().unwrap();
        for v in 0..pos.len() {
            let m = blend(&joint_mats, joints[v], jw[v]);
            pos[v] = m.transform_point3(pos[v]);
            if let Some(nn) = nrm.as_mut() {
                let nm = Mat3::from_mat4(m).inverse().transpose();
                nn[v] = (nm * nn[v]).normalize_or_zero();
            }
        }
    } else if let Some(nn) = nrm.as_mut() {
        for p in nn.iter_mut() {
            *p = p.normalize_or_zero();
        }
    }
    Some((pos, nrm))
}

fn blend(mats: &[Mat4], j: [u16; 4], w: Vec4) -> Mat4 {
    let sum = w.x + w.y + w.z + w.w;
    let w = if sum > 0.0 {
        w / sum
    } else {
        Vec4::new(1.0, 0.0, 0.0, 0.0)
    };
    let mut m = Mat4::ZERO;
    for k in 0..4 {
        if w[k] != 0.0
            && let Some(jm) = mats.get(j[k] as usize)
        {
            m += *jm * w[k];
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ch(
        interp: Interpolation,
        target: ChannelTarget,
        times: Vec<f32>,
        values: Vec<f32>,
        n: usize,
    ) -> Channel {
        Channel {
            node: NodeId(0),
            target,
            interpolation: interp,
            times,
            values,
            components: n,
        }
    }

    #[test]
    fn linear_step_and_clamping() {
        let c = ch(
            Interpolation::Linear,
            ChannelTarget::Translation,
            vec![1.0, 3.0],
            vec![0., 0., 0., 2., 4., 6.],
            3,
        );
        assert_eq!(evaluate_channel(&c, 0.0), vec![0., 0., 0.]);
        assert_eq!(evaluate_channel(&c, 2.0), vec![1., 2., 3.]);
        assert_eq!(evaluate_channel(&c, 9.0), vec![2., 4., 6.]);
        let s = Channel {
            interpolation: Interpolation::Step,
            ..c
        };
        assert_eq!(evaluate_channel(&s, 2.9), vec![0., 0., 0.]);
        assert_eq!(evaluate_channel(&s, 3.0), vec![2., 4., 6.]);
    }

    #[test]
    fn slerp_takes_the_short_way() {
        let a = Quat::from_rotation_y(0.1);
        let b = -Quat::from_rotation_y(0.3); // same rotation, opposite hemisphere
        let c = ch(
            Interpolation::Linear,
            ChannelTarget::Rotation,
            vec![0.0, 1.0],
            vec![a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w],
            4,
        );
        let v = evaluate_channel(&c, 0.5);
        let q = Quat::from_xyzw(v[0], v[1], v[2], v[3]);
        assert!(q.angle_between(Quat::from_rotation_y(0.2)) < 1e-4);
    }

    #[test]
    fn cubic_spline_hits_keys_and_hermite_midpoint() {
        // One component, keys at 0 and 2 with values 0 and 1, out-tangent 1 at key 0, in-tangent 0 at key 1.
        // Layout per key: in, value, out.
        let c = ch(
            Interpolation::CubicSpline,
            ChannelTarget::Translation,
            vec![0.0, 2.0],
            vec![0., 0., 1., 0., 1., 0.],
            1,
        );
        assert_eq!(evaluate_channel(&c, 0.0), vec![0.0]);
        assert_eq!(evaluate_channel(&c, 2.0), vec![1.0]);
        // s = 0.5: h00=.5 h10=.125 h01=.5 h11=-.125; v = .5*0 + .125*2*1 + .5*1 + 0 = 0.75
        assert!((evaluate_channel(&c, 1.0)[0] - 0.75).abs() < 1e-6);
    }
}
