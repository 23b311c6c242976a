//! Scenes generated in code for benchmarks (deterministic): a height-field terrain with
//! icospheres scattered above it, as in ../shared/DEPENDENCIES.md §4.
//!
//! - terrain: 100 × 100 units centred on the origin in the XZ plane, `cells × cells`
//!   quads (2 triangles each), height a sum of three sine octaves (|h| ≤ 4.5);
//! - `spheres` icospheres of subdivision `level` (20·4^level triangles), radius 1–5,
//!   scattered above the terrain (PCG32 seed 1), and one large one (radius 8, subdivision
//!   `big_level`) in the middle.
//!
//! [`TerrainSpheres::SMALL`] has 95,360 triangles, [`TerrainSpheres::LARGE`] 1,024,000.
//! The scene has one white diffuse material, no camera (framed automatically) and a
//! uniform white environment light.

use super::desc::{Material, MaterialId, Mesh, MeshId, Node, NodeId, Primitive, SceneDesc, Trs};
use crate::color::Rgb;
use crate::math::Vec3;
use crate::sampling::rng::Pcg32;

/// Parameters of the terrain-and-spheres scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TerrainSpheres {
    pub cells: u32,
    pub spheres: u32,
    pub level: u32,
    pub big_level: u32,
}

impl TerrainSpheres {
    /// 200 × 200 cells + 8 spheres (level 3) + 1 (level 4): 95,360 triangles.
    pub const SMALL: TerrainSpheres = TerrainSpheres {
        cells: 200,
        spheres: 8,
        level: 3,
        big_level: 4,
    };
    /// 640 × 640 cells + 24 spheres (level 4) + 1 (level 6): 1,024,000 triangles.
    pub const LARGE: TerrainSpheres = TerrainSpheres {
        cells: 640,
        spheres: 24,
        level: 4,
        big_level: 6,
    };

    /// The sphere layout of SMALL (below 500k triangles) or LARGE, with the terrain
    /// resolution chosen so the total is as close as possible to `n` (at least 1 cell).
    pub fn with_triangles(n: u64) -> TerrainSpheres {
        let base = if n < 500_000 {
            Self::SMALL
        } else {
            Self::LARGE
        };
        let spheres = base.spheres as u64 * icosphere_triangles(base.level)
            + icosphere_triangles(base.big_level);
        let terrain = n.saturating_sub(spheres) as f64;
        let cells = ((terrain / 2.0).sqrt().round() as u32).max(1);
        TerrainSpheres { cells, ..base }
    }

    pub fn triangle_count(&self) -> u64 {
        2 * (self.cells as u64).pow(2)
            + self.spheres as u64 * icosphere_triangles(self.level)
            + icosphere_triangles(self.big_level)
    }

    /// The scene description.
    pub fn scene(&self) -> SceneDesc {
        let terrain = terrain(self.cells);
        let mut nodes = vec![Node {
            name: "terrain".into(),
            mesh: Some(MeshId(0)),
            ..Default::default()
        }];
        let mut rng = Pcg32::new(1, 0);
        for k in 0..self.spheres {
            let r = 1.0 + 4.0 * rng.next_f32();
            let x = -45.0 + 90.0 * rng.next_f32();
            let z = -45.0 + 90.0 * rng.next_f32();
            let y = height(x, z) + r + 5.0 * rng.next_f32();
            nodes.push(sphere_node(
                format!("sphere{k}"),
                MeshId(1),
                Vec3::new(x, y, z),
                r,
            ));
        }
        nodes.push(sphere_node(
            "big sphere".into(),
            MeshId(2),
            Vec3::new(0.0, height(0.0, 0.0) + 9.0, 0.0),
            8.0,
        ));
        let roots = (0..nodes.len() as u32).map(NodeId).collect();
        let mesh = |name: &str, p: Primitive| Mesh {
            name: name.into(),
            primitives: vec![Primitive {
                material: Some(MaterialId(0)),
                ..p
            }],
            weights: vec![],
        };
        SceneDesc {
            name: format!(
                "generated terrain {0}x{0} + {1} spheres: {2} triangles",
                self.cells,
                self.spheres + 1,
                self.triangle_count()
            ),
            nodes,
            roots,
            meshes: vec![
                mesh("terrain", terrain),
                mesh("sphere", icosphere(self.level)),
                mesh("big sphere", icosphere(self.big_level)),
            ],
            materials: vec![Material::diffuse("white", Rgb::splat(0.7))],
            environment: Some(crate::light::Environment::uniform(Rgb::splat(1.0))),
            ..Default::default()
        }
    }
}

fn sphere_node(name: String, mesh: MeshId, at: Vec3, r: f32) -> Node {
    Node {
        name,
        mesh: Some(mesh),
        transform: Trs {
            translation: at,
            scale: Vec3::splat(r),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Terrain height at (x, z): three sine octaves, |h| ≤ 4.5.
pub fn height(x: f32, z: f32) -> f32 {
    2.5 * (0.08 * x).sin() * (0.07 * z).cos()
        + 1.5 * (0.21 * x + 1.0).sin() * (0.17 * z + 2.0).sin()
        + 0.5 * (0.55 * x + 0.3 * z).sin()
}

fn terrain(cells: u32) -> Primitive {
    let n = cells + 1;
    let mut positions = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let x = -50.0 + 100.0 * i as f32 / cells as f32;
            let z = -50.0 + 100.0 * j as f32 / cells as f32;
            positions.push(Vec3::new(x, height(x, z), z));
        }
    }
    let mut indices = Vec::with_capacity(2 * (cells * cells) as usize);
    for j in 0..cells {
        for i in 0..cells {
            let a = j * n + i;
            let (b, c, d) = (a + 1, a + n, a + n + 1);
            // Counter-clockwise seen from above (+Y).
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    Primitive {
        positions,
        indices,
        ..Default::default()
    }
}

fn icosphere_triangles(level: u32) -> u64 {
    20 * 4u64.pow(level)
}

/// A unit icosphere: an icosahedron subdivided `level` times (each triangle into 4),
/// vertices projected to the sphere; unshared vertices, outward winding.
pub fn icosphere(level: u32) -> Primitive {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        Vec3::new(-1.0, t, 0.0),
        Vec3::new(1.0, t, 0.0),
        Vec3::new(-1.0, -t, 0.0),
        Vec3::new(1.0, -t, 0.0),
        Vec3::new(0.0, -1.0, t),
        Vec3::new(0.0, 1.0, t),
        Vec3::new(0.0, -1.0, -t),
        Vec3::new(0.0, 1.0, -t),
        Vec3::new(t, 0.0, -1.0),
        Vec3::new(t, 0.0, 1.0),
        Vec3::new(-t, 0.0, -1.0),
        Vec3::new(-t, 0.0, 1.0),
    ]
    .map(|p| p.normalize());
    let faces: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut tris: Vec<[Vec3; 3]> = faces.iter().map(|f| f.map(|i| v[i])).collect();
    for _ in 0..level {
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let (ab, bc, ca) = (
                (a + b).normalize(),
                (b + c).normalize(),
                (c + a).normalize(),
            );
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let indices = (0..tris.len() as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    Primitive {
        normals: Some(positions.clone()),
        positions,
        indices,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_have_the_documented_triangle_counts() {
        assert_eq!(TerrainSpheres::SMALL.triangle_count(), 95_360);
        assert_eq!(TerrainSpheres::LARGE.triangle_count(), 1_024_000);
        assert_eq!(
            TerrainSpheres::with_triangles(1_024_000),
            TerrainSpheres::LARGE
        );
        assert_eq!(
            TerrainSpheres::with_triangles(95_360),
            TerrainSpheres::SMALL
        );
        let s = TerrainSpheres::SMALL.scene();
        let n: usize = s
            .nodes
            .iter()
            .filter_map(|n| n.mesh)
            .map(|m| s.meshes[m.index()].primitives[0].indices.len())
            .sum();
        assert_eq!(n, 95_360);
    }

    #[test]
    fn icosphere_is_outward_and_unit() {
        let p = icosphere(2);
        for t in &p.indices {
            let [a, b, c] = t.map(|i| p.positions[i as usize]);
            assert!((a.length() - 1.0).abs() < 1e-5);
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
        }
    }
}
