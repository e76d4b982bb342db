//! Loop subdivision of triangle meshes (pbrt-v4's `loopsubdiv` shape): each level splits every
//! triangle into four, moving the old ("even") vertices by Loop's one-ring rule
//! (`(1 − nβ) v + β Σ ring`, β = 3/16 at valence 3, 3/(8n) otherwise, 1/16 at the regular valence
//! 6) or, on the boundary, by `¾ v + ⅛ (both boundary neighbours)`, and placing the new
//! ("odd") vertices at `⅜ (edge ends) + ⅛ (the two opposite vertices)` (the midpoint on a
//! boundary edge). After the last level the vertices are pushed to their positions on the limit
//! surface (one-ring weight `1/(n + 3/(8β))`, boundary weight ⅕), and each gets the limit
//! surface's normal from its two limit tangents, with pbrt-v4's rules and signs, so that a
//! subdivided pbrt scene shades as it does in pbrt.
//!
//! The control mesh must be a consistently oriented manifold (every edge in one or two
//! triangles, traversed in opposite directions; every vertex's triangles one fan): anything
//! else is an error naming what is wrong, as pbrt's pointer walks would not terminate or would
//! read past the mesh.

use crate::math::{Vec3, PI};
use std::collections::HashMap;

/// No neighbour across an edge (a boundary edge).
const NONE: u32 = u32::MAX;

/// The most triangles a subdivision may produce (2²⁵: about 1.6 GB of mesh at the end).
pub const MAX_TRIANGLES: usize = 1 << 25;

/// A subdivided mesh: limit positions, limit normals (unit), triangles.
#[derive(Clone, Debug)]
pub struct Subdivided {
    /// Vertex positions on the limit surface.
    pub positions: Vec<Vec3>,
    /// Unit normals of the limit surface at the vertices.
    pub normals: Vec<Vec3>,
    /// Triangles (counter-clockwise as the control mesh's).
    pub indices: Vec<[u32; 3]>,
}

/// A control mesh's topology: per triangle, its vertices and the triangle across each edge
/// `(v[i], v[i+1])`.
struct Topology {
    faces: Vec<[u32; 3]>,
    across: Vec<[u32; 3]>,
    /// One triangle holding each vertex.
    start: Vec<u32>,
}

#[inline]
fn next(i: usize) -> usize {
    (i + 1) % 3
}

#[inline]
fn prev(i: usize) -> usize {
    (i + 2) % 3
}

impl Topology {
    fn new(faces: Vec<[u32; 3]>, n_vertices: usize) -> Result<Topology, String> {
        let mut across = vec![[NONE; 3]; faces.len()];
        let mut start = vec![NONE; n_vertices];
        // Edge (low, high) → (face, edge number, direction low→high, faces seen).
        let mut edges: HashMap<(u32, u32), (u32, usize, bool, u32)> = HashMap::with_capacity(faces.len() * 2);
        for (f, v) in faces.iter().enumerate() {
            if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
                return Err(format!("triangle {f} repeats a vertex ({} {} {})", v[0], v[1], v[2]));
            }
            for (k, &vk) in v.iter().enumerate() {
                start[vk as usize] = f as u32;
                let (a, b) = (vk, v[next(k)]);
                let key = (a.min(b), a.max(b));
                let forward = a < b;
                match edges.get_mut(&key) {
                    None => {
                        edges.insert(key, (f as u32, k, forward, 1));
                    }
                    Some(e) => {
                        e.3 += 1;
                        if e.3 > 2 {
                            return Err(format!("the edge between vertices {a} and {b} is in more than two triangles"));
                        }
                        if e.2 == forward {
                            return Err(format!(
                                "triangles {} and {f} traverse the edge between vertices {a} and {b} in the same \
                                 direction: the mesh is not consistently oriented",
                                e.0
                            ));
                        }
                        across[e.0 as usize][e.1] = f as u32;
                        across[f][k] = e.0;
                    }
                }
            }
        }
        Ok(Topology { faces, across, start })
    }

    #[inline]
    fn vnum(&self, f: u32, v: u32) -> usize {
        let fv = self.faces[f as usize];
        (0..3).find(|&i| fv[i] == v).expect("the walk stays in the vertex's triangles")
    }

    /// The ordered one-ring of vertex `v` (pbrt's order) and whether `v` is on the boundary;
    /// `fan` is the number of triangles holding `v`.
    fn ring(&self, v: u32, fan: u32) -> Result<(Vec<u32>, bool), String> {
        let start = self.start[v as usize];
        let next_face = |f: u32| self.across[f as usize][self.vnum(f, v)];
        let prev_face = |f: u32| self.across[f as usize][prev(self.vnum(f, v))];
        let next_vert = |f: u32| self.faces[f as usize][next(self.vnum(f, v))];
        let prev_vert = |f: u32| self.faces[f as usize][prev(self.vnum(f, v))];
        let not_a_fan = || format!("the triangles around vertex {v} do not form one fan (a non-manifold vertex)");
        // Interior: the walk across (v, next) edges returns to the start after `fan` steps.
        let mut ring = Vec::with_capacity(fan as usize + 1);
        let mut f = start;
        loop {
            ring.push(next_vert(f));
            f = next_face(f);
            if f == NONE || f == start || ring.len() > fan as usize {
                break;
            }
        }
        if f == start {
            if ring.len() != fan as usize {
                return Err(not_a_fan());
            }
            return Ok((ring, false));
        }
        if f != NONE {
            return Err(not_a_fan());
        }
        // Boundary: forward to the last triangle, then back across (prev, v) edges.
        let mut f = start;
        let mut steps = 0;
        while next_face(f) != NONE {
            f = next_face(f);
            steps += 1;
            if steps > fan {
                return Err(not_a_fan());
            }
        }
        ring.clear();
        ring.push(next_vert(f));
        let mut faces = 0;
        while f != NONE {
            ring.push(prev_vert(f));
            f = prev_face(f);
            faces += 1;
            if faces > fan {
                return Err(not_a_fan());
            }
        }
        if faces != fan {
            return Err(not_a_fan());
        }
        Ok((ring, true))
    }

    /// Every vertex's ring and boundary flag.
    fn rings(&self, n_vertices: usize) -> Result<Vec<(Vec<u32>, bool)>, String> {
        let mut fan = vec![0u32; n_vertices];
        for f in &self.faces {
            for &v in f {
                fan[v as usize] += 1;
            }
        }
        (0..n_vertices as u32).map(|v| self.ring(v, fan[v as usize])).collect()
    }
}

/// Loop's β for valence `n`.
#[inline]
fn beta(n: usize) -> f32 {
    if n == 3 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * n as f32)
    }
}

/// `(1 − nβ) p + β Σ ring`.
#[inline]
fn one_ring(p: &[Vec3], v: usize, ring: &[u32], beta: f32) -> Vec3 {
    let sum: Vec3 = ring.iter().map(|&r| p[r as usize]).sum();
    (1.0 - ring.len() as f32 * beta) * p[v] + beta * sum
}

/// `(1 − 2β) p + β (first + last of the ring)`: the boundary rule.
#[inline]
fn boundary(p: &[Vec3], v: usize, ring: &[u32], beta: f32) -> Vec3 {
    (1.0 - 2.0 * beta) * p[v] + beta * (p[ring[0] as usize] + p[ring[ring.len() - 1] as usize])
}

/// Loop-subdivides the triangles `indices` over `positions` `levels` times and projects the
/// result to the limit surface. Vertices no triangle uses are left out.
pub fn loop_subdivide(positions: &[Vec3], indices: &[[u32; 3]], levels: u32) -> Result<Subdivided, String> {
    if indices.is_empty() {
        return Err("the control mesh has no triangles".into());
    }
    if indices.len().saturating_mul(4usize.saturating_pow(levels)) > MAX_TRIANGLES {
        return Err(format!(
            "{levels} levels of subdivision of {} triangles would make more than {MAX_TRIANGLES}",
            indices.len()
        ));
    }
    // Keep the vertices the triangles use, renumbered in order of use.
    let mut remap = vec![NONE; positions.len()];
    let mut p = Vec::new();
    let mut faces = Vec::with_capacity(indices.len());
    for t in indices {
        let mut f = [0; 3];
        for (k, &i) in t.iter().enumerate() {
            let slot = remap.get_mut(i as usize).ok_or_else(|| format!("vertex index {i} is out of range"))?;
            if *slot == NONE {
                *slot = p.len() as u32;
                p.push(positions[i as usize]);
            }
            f[k] = *slot;
        }
        faces.push(f);
    }
    if p.iter().any(|v| !v.is_finite()) {
        return Err("a control vertex is not finite".into());
    }
    let mut topo = Topology::new(faces, p.len())?;
    let mut rings = topo.rings(p.len())?;
    for _ in 0..levels {
        // Even vertices keep their indices; odd ones follow, one per edge.
        let mut q: Vec<Vec3> = (0..p.len())
            .map(|v| {
                let (ring, on_boundary) = &rings[v];
                match (*on_boundary, ring.len()) {
                    (true, _) => boundary(&p, v, ring, 1.0 / 8.0),
                    (false, 6) => one_ring(&p, v, ring, 1.0 / 16.0),
                    (false, n) => one_ring(&p, v, ring, beta(n)),
                }
            })
            .collect();
        let mut edge_vertex: HashMap<(u32, u32), u32> = HashMap::with_capacity(topo.faces.len() * 2);
        let mut new_faces = Vec::with_capacity(topo.faces.len() * 4);
        for (f, v) in topo.faces.iter().enumerate() {
            let mut e = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (v[k], v[next(k)]);
                let key = (a.min(b), a.max(b));
                e[k] = *edge_vertex.entry(key).or_insert_with(|| {
                    let (pa, pb) = (p[a as usize], p[b as usize]);
                    let across = topo.across[f][k];
                    q.push(if across == NONE {
                        0.5 * (pa + pb)
                    } else {
                        let other = |g: [u32; 3]| g.into_iter().find(|&x| x != a && x != b).expect("a triangle");
                        let (o1, o2) = (other(*v), other(topo.faces[across as usize]));
                        0.375 * (pa + pb) + 0.125 * (p[o1 as usize] + p[o2 as usize])
                    });
                    q.len() as u32 - 1
                });
            }
            new_faces.push([v[0], e[0], e[2]]);
            new_faces.push([e[0], v[1], e[1]]);
            new_faces.push([e[2], e[1], v[2]]);
            new_faces.push([e[0], e[1], e[2]]);
        }
        p = q;
        topo = Topology::new(new_faces, p.len())?;
        rings = topo.rings(p.len())?;
    }
    // Limit positions.
    let limit: Vec<Vec3> = (0..p.len())
        .map(|v| {
            let (ring, on_boundary) = &rings[v];
            if *on_boundary {
                boundary(&p, v, ring, 0.2)
            } else {
                let n = ring.len();
                one_ring(&p, v, ring, 1.0 / (n as f32 + 3.0 / (8.0 * beta(n))))
            }
        })
        .collect();
    // Limit normals from the limit tangents (pbrt-v4's rules, on the limit positions).
    let mut face_normal = vec![Vec3::ZERO; limit.len()];
    for f in &topo.faces {
        let [a, b, c] = f.map(|i| limit[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in f {
            face_normal[i as usize] += n;
        }
    }
    let normals = (0..limit.len())
        .map(|v| {
            let (ring, on_boundary) = &rings[v];
            let r = |j: usize| limit[ring[j] as usize];
            let n = ring.len();
            let (s, t) = if !on_boundary {
                let mut s = Vec3::ZERO;
                let mut t = Vec3::ZERO;
                for j in 0..n {
                    let a = 2.0 * PI * j as f32 / n as f32;
                    s += a.cos() * r(j);
                    t += a.sin() * r(j);
                }
                (s, t)
            } else {
                let s = r(n - 1) - r(0);
                let p = limit[v];
                let t = match n {
                    2 => r(0) + r(1) - 2.0 * p,
                    3 => r(1) - p,
                    4 => -r(0) + 2.0 * r(1) + 2.0 * r(2) - r(3) - 2.0 * p,
                    _ => {
                        let theta = PI / (n - 1) as f32;
                        let mut t = theta.sin() * (r(0) + r(n - 1));
                        for k in 1..n - 1 {
                            t += (2.0 * theta.cos() - 2.0) * (k as f32 * theta).sin() * r(k);
                        }
                        -t
                    }
                };
                (s, t)
            };
            let n = s.cross(t).normalize_or_zero();
            // A degenerate tangent pair: the vertex's triangles' normal, facing as the tangents
            // would for a consistent neighbourhood.
            if n == Vec3::ZERO {
                face_normal[v].normalize_or(Vec3::Z)
            } else {
                n
            }
        })
        .collect();
    Ok(Subdivided { positions: limit, normals, indices: topo.faces })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        // Counter-clockwise seen from outside.
        let f = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (p, f)
    }

    /// Counts, closedness and symmetry: an octahedron's subdivision has 8·4ᴸ triangles, every
    /// edge in two of them, and stays symmetric; the limit surface is smooth and shrinks toward
    /// the centre (Loop's scheme is approximating): every vertex at a distance in (0.3, 1) (inside the hull).
    #[test]
    fn subdivided_octahedron() {
        let (p, f) = octahedron();
        for levels in 0..4 {
            let s = loop_subdivide(&p, &f, levels).unwrap();
            assert_eq!(s.indices.len(), 8 * 4usize.pow(levels));
            assert_eq!(s.positions.len(), 4 * 4usize.pow(levels) + 2, "V = E − F + 2 on a sphere");
            let t = Topology::new(s.indices.clone(), s.positions.len()).unwrap();
            assert!(t.across.iter().flatten().all(|&a| a != NONE), "closed");
            let r: Vec<f32> = s.positions.iter().map(|v| v.length()).collect();
            assert!(r.iter().all(|&r| r > 0.3 && r < 1.0), "{r:?}");
            // The six original vertices (regular of valence 4: all alike) share one radius.
            assert!((r[0] - r[5]).abs() < 1e-5 && (r[2] - r[4]).abs() < 1e-5);
            // Normals point outward for this counter-clockwise mesh? pbrt's sign: the ring runs
            // clockwise seen from outside, and Cross(S, T) then points inward.
            for (v, n) in s.positions.iter().zip(&s.normals) {
                assert!((n.length() - 1.0).abs() < 1e-4);
                assert!(n.dot(v.normalize()) < -0.9, "normal {n} at {v}");
            }
        }
        // Limit position of a valence-4 vertex after no subdivision: γ = 1/(4 + 3/(8β)), β = 3/32.
        let s = loop_subdivide(&p, &f, 0).unwrap();
        let gamma = 1.0 / (4.0 + 3.0 / (8.0 * 3.0 / 32.0));
        let expected = (1.0 - 4.0 * gamma) * 1.0; // the ring (±y, ±z around +x) sums to zero
        assert!((s.positions[0] - Vec3::X * expected).length() < 1e-6, "{}", s.positions[0]);
    }

    /// A flat open grid stays flat; its boundary follows the boundary rules (a straight
    /// boundary stays straight), and the interior normals are the plane's (pbrt's sign).
    #[test]
    fn flat_patch_with_boundary() {
        let n = 4;
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push(Vec3::new(i as f32, j as f32, 0.0));
            }
        }
        let id = |i: u32, j: u32| j * (n + 1) + i;
        let mut f = Vec::new();
        for j in 0..n {
            for i in 0..n {
                f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let s = loop_subdivide(&p, &f, 2).unwrap();
        assert_eq!(s.indices.len(), f.len() * 16);
        for (v, nrm) in s.positions.iter().zip(&s.normals) {
            assert!(v.z.abs() < 1e-6);
            assert!(v.x >= -1e-5 && v.x <= n as f32 + 1e-5 && v.y >= -1e-5 && v.y <= n as f32 + 1e-5);
            assert!((nrm.z.abs() - 1.0).abs() < 1e-4, "{nrm} at {v}");
        }
        // The boundary is the cubic B-spline of the boundary polygon (pbrt has no corner rule:
        // corners round off): on the line y = 0 exactly where its four control points are,
        // x ∈ [1, 3], the limit points at spacing ¼ there.
        let on_edge: Vec<f32> = s.positions.iter().filter(|v| v.y.abs() < 1e-6).map(|v| v.x).collect();
        assert_eq!(on_edge.len(), 9, "{on_edge:?}");
        assert!(on_edge.iter().all(|&x| (1.0 - 1e-5..=3.0 + 1e-5).contains(&x)), "{on_edge:?}");
    }

    #[test]
    fn bad_control_meshes_are_errors() {
        let (p, mut f) = octahedron();
        f[0] = [0, 4, 2];
        let e = loop_subdivide(&p, &f, 1).unwrap_err();
        assert!(e.contains("not consistently oriented"), "{e}");
        let e = loop_subdivide(&p, &[[0, 0, 1]], 1).unwrap_err();
        assert!(e.contains("repeats a vertex"), "{e}");
        let e = loop_subdivide(&p, &[[0, 1, 2], [0, 2, 1], [1, 0, 2]], 1).unwrap_err();
        assert!(e.contains("more than two") || e.contains("oriented"), "{e}");
        let (p, f) = octahedron();
        assert!(loop_subdivide(&p, &f, 30).unwrap_err().contains("more than"));
        // Two fans sharing one vertex (a bowtie).
        let p2 = vec![Vec3::ZERO, Vec3::X, Vec3::Y, -Vec3::X, -Vec3::Y];
        let e = loop_subdivide(&p2, &[[0, 1, 2], [0, 3, 4]], 1).unwrap_err();
        assert!(e.contains("fan"), "{e}");
    }
}
