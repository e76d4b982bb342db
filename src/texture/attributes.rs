//! Mitsuba's texture attributes: textures nested by name in a `<shape>`
//! (`<texture type="bitmap" name="face_albedo">`), which the `mesh_attribute` textures of that
//! shape's BSDF read by the same name. Mitsuba's `Shape::eval_attribute` order holds: a mesh's
//! own vertex and face attributes first, then the shape's texture attributes; any shape may
//! carry them, analytic ones included.

use super::{TexPoint, Texture};
use crate::math::Rgb;

/// A shape's named textures.
#[derive(Clone, Debug, Default)]
pub struct TextureAttributes {
    named: Vec<(String, Texture)>,
}

impl TextureAttributes {
    /// Adds `texture` as attribute `name`, replacing one of that name (as Mitsuba's
    /// `add_texture_attribute`).
    pub fn insert(&mut self, name: impl Into<String>, texture: Texture) {
        let name = name.into();
        match self.named.iter_mut().find(|(n, _)| *n == name) {
            Some(slot) => slot.1 = texture,
            None => self.named.push((name, texture)),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.named.is_empty()
    }

    /// The attribute `name`, if the shape has it.
    pub fn get(&self, name: &str) -> Option<&Texture> {
        self.named.iter().find(|(n, _)| n == name).map(|(_, t)| t)
    }

    /// The colour of attribute `name` at `at` (whose own `mesh_attribute` textures read the
    /// mesh and the other attributes, as in Mitsuba: [`TextureAttributes::cycle`] is what the
    /// scene builder rejects so that this ends).
    pub fn eval(&self, name: &str, at: &TexPoint) -> Option<Rgb> {
        Some(self.get(name)?.eval_at(at))
    }

    /// The scalar value of attribute `name` at `at` ([`Texture::eval_scalar`], Mitsuba's
    /// `eval_attribute_1`).
    pub fn eval_scalar(&self, name: &str, at: &TexPoint) -> Option<f32> {
        Some(self.get(name)?.eval_scalar(at))
    }

    /// An attribute that reads itself through `mesh_attribute` textures (directly or along a
    /// chain of attributes), if one does; `mesh_has(name)` tells the names the mesh answers
    /// itself (those end a chain). Mitsuba would recurse without end on such a shape.
    pub fn cycle(&self, mesh_has: impl Fn(&str) -> bool) -> Option<&str> {
        // Depth-first search over the attributes, coloured 0 (unseen), 1 (on the path), 2 (done).
        let index = |name: &str| self.named.iter().position(|(n, _)| n == name);
        let mut colour = vec![0u8; self.named.len()];
        for start in 0..self.named.len() {
            if colour[start] != 0 {
                continue;
            }
            // (attribute, its reads not yet followed)
            let mut stack: Vec<(usize, Vec<&str>)> = vec![(start, self.named[start].1.mesh_attributes())];
            colour[start] = 1;
            while let Some(top) = stack.last_mut() {
                let at = top.0;
                match top.1.pop() {
                    None => {
                        colour[at] = 2;
                        stack.pop();
                    }
                    Some(name) if mesh_has(name) => {}
                    Some(name) => match index(name) {
                        Some(next) if colour[next] == 1 => return Some(&self.named[next].0),
                        Some(next) if colour[next] == 0 => {
                            colour[next] = 1;
                            stack.push((next, self.named[next].1.mesh_attributes()));
                        }
                        _ => {}
                    },
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh::{MeshAttribute, MeshPoint};
    use crate::geometry::TriangleMesh;
    use crate::math::{Mat3, Vec2};

    fn checker() -> Texture {
        Texture::Checkerboard {
            color0: Box::new(Texture::Constant(Rgb::new(1.0, 0.0, 0.0))),
            color1: Box::new(Texture::Constant(Rgb::new(0.0, 0.0, 0.5))),
            to_uv: Mat3::IDENTITY,
        }
    }

    /// A `mesh_attribute` texture reads the shape's texture attribute where the mesh has no
    /// attribute of that name (colour and scalar, times its scale), the mesh's own attribute
    /// where it has one, and nothing (0) where neither is.
    #[test]
    fn mesh_attribute_textures_read_the_shape_textures_after_the_mesh() {
        let mut attrs = TextureAttributes::default();
        attrs.insert("face_color", Texture::Constant(Rgb::ONE));
        attrs.insert("face_color", checker());
        attrs.insert("vertex_color", Texture::Constant(Rgb::splat(9.0)));
        assert!(!attrs.is_empty() && attrs.get("face_other").is_none());
        let read = |name: &str| Texture::MeshAttribute { name: name.into(), scale: 2.0 };
        let (uv0, uv1) = (Vec2::new(0.25, 0.25), Vec2::new(0.75, 0.25));
        let at = |uv| TexPoint { textures: Some(&attrs), ..TexPoint::at_uv(uv) };
        assert_eq!(read("face_color").eval_at(&at(uv0)), Rgb::new(2.0, 0.0, 0.0));
        assert_eq!(read("face_color").eval_at(&at(uv1)), Rgb::new(0.0, 0.0, 1.0));
        // The scalar lookup is the attribute's own (Mitsuba's checkerboard swaps its colours
        // there), times the scale.
        assert_eq!(read("face_color").eval_scalar(&at(uv0)), 2.0 * checker().eval_scalar(&at(uv0)));
        assert_eq!(read("face_other").eval_at(&at(uv0)), Rgb::ZERO);
        assert_eq!(read("face_color").eval_at(&TexPoint::at_uv(uv0)), Rgb::ZERO);
        // A mesh's own attribute wins over a texture of the same name.
        let mut mesh = TriangleMesh::rectangle();
        let n = mesh.positions.len();
        mesh.attributes.push(MeshAttribute {
            name: "vertex_color".into(),
            per_face: false,
            values: vec![crate::math::Vec3::splat(0.5); n],
        });
        let point = MeshPoint { mesh: &mesh, tri: 0, bary: Vec2::new(0.2, 0.3) };
        let on_mesh = TexPoint { mesh: Some(&point), ..at(uv0) };
        assert_eq!(read("vertex_color").eval_at(&on_mesh), Rgb::ONE);
        assert_eq!(read("face_color").eval_at(&on_mesh), Rgb::new(2.0, 0.0, 0.0));
    }

    /// Attributes may read one another (evaluated through the chain, as Mitsuba does); a chain
    /// that comes back to where it started is found, and a read the mesh answers ends a chain.
    #[test]
    fn attributes_read_one_another_and_cycles_are_found() {
        let read = |name: &str| Texture::MeshAttribute { name: name.into(), scale: 0.5 };
        let mut attrs = TextureAttributes::default();
        attrs.insert("face_a", read("face_b"));
        attrs.insert("face_b", Texture::Constant(Rgb::splat(4.0)));
        let at = TexPoint { textures: Some(&attrs), ..TexPoint::at_uv(Vec2::ZERO) };
        assert_eq!(read("face_a").eval_at(&at), Rgb::ONE);
        assert_eq!(attrs.cycle(|_| false), None);
        attrs.insert("face_b", Texture::Scale(Box::new([read("face_c"), Texture::Constant(Rgb::ONE)])));
        attrs.insert("face_c", read("face_a"));
        assert!(attrs.cycle(|_| false).is_some());
        // The mesh answers face_c itself: no cycle through the attributes.
        assert_eq!(attrs.cycle(|n| n == "face_c"), None);
        let mut own = TextureAttributes::default();
        own.insert("face_self", read("face_self"));
        assert_eq!(own.cycle(|_| false), Some("face_self"));
    }
}
