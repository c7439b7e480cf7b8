//! The CPU's eight-wide BVH: one node visit tests up to eight child boxes. The tree is
//! collapsed from the binary SAH tree (`bvh::build_trees`, the collapse of least node area);
//! this module has its node's slab test, and [`one_for_one`], the four-wide tree as wide nodes
//! (a tree built by hand, `examples/lane_occupancy.rs`).
//!
//! The traversal's cost on the CPU is the latency of each node's test-decide-load chain, not the
//! instruction count (docs/journal/2026-11-23_cpu_traversal.md): a node of eight children is two
//! independent four-wide slab tests, which the core runs side by side in about the time of one, and
//! the tree has about half the levels. The leaves are the four-wide tree's own (the same `prims`
//! ranges, starting at multiples of four for the triangle packs), in the same order, so a
//! traversal reports the same hits, and the nearest is the same primitive (ties in t go to the
//! lower primitive id, `bvh::nearer`).

use crate::layout::cpu::ROWS;
pub use crate::layout::cpu::WIDTH;
use crate::layout::{BvhNode, WideNode, EMPTY_SLOT};
use crate::math::geometry::intersect_boxes4;
use arrayvec::ArrayVec;
use glam::Vec3;

/// One child slot of a four-wide node: its box, its `child` and its `count`.
#[derive(Clone, Copy)]
struct Slot {
    lo: Vec3,
    hi: Vec3,
    child: u32,
    count: u32,
}

fn slots(node: &BvhNode) -> ArrayVec<Slot, 4> {
    (0..4)
        .filter(|&c| node.count[c] != EMPTY_SLOT)
        .map(|c| {
            let (lo, hi) = node.child_bounds(c);
            Slot {
                lo,
                hi,
                child: node.child[c],
                count: node.count[c],
            }
        })
        .collect()
}

/// The four-wide tree itself as wide nodes, one for one, each with its four slots in the first
/// row and the other rows empty: the CPU's traversal over it visits exactly the nodes, in
/// exactly the order, that the shader's traversal of the four-wide tree visits, so
/// `examples/lane_occupancy.rs` counts the shader's work with it.
pub fn one_for_one(nodes: &[BvhNode]) -> Vec<WideNode> {
    let mut wide = Vec::with_capacity(nodes.len());
    if !nodes.is_empty() {
        append(nodes, 0, &mut wide);
    }
    wide
}

/// Appends the wide node of four-wide node `index` (its slots in the first row) and its
/// descendants, depth first; returns its index.
fn append(nodes: &[BvhNode], index: usize, wide: &mut Vec<WideNode>) -> u32 {
    let open = slots(&nodes[index]);
    let at = wide.len();
    wide.push(WideNode::default());
    let mut node = WideNode::default();
    for (c, s) in open.iter().enumerate() {
        let (h, l) = (c / 4, c % 4);
        node.min_x[h][l] = s.lo.x;
        node.min_y[h][l] = s.lo.y;
        node.min_z[h][l] = s.lo.z;
        node.max_x[h][l] = s.hi.x;
        node.max_y[h][l] = s.hi.y;
        node.max_z[h][l] = s.hi.z;
        node.count[c] = s.count;
        node.child[c] = if s.count == 0 {
            append(nodes, s.child as usize, wide)
        } else {
            s.child
        };
    }
    wide[at] = node;
    at as u32
}

/// The slab test of a ray against a wide node's boxes, row by row
/// ([`intersect_boxes4`]): per slot, the distance at which the ray enters the box (0 when it
/// starts inside) and a mask of the occupied slots it enters no later than `t_max`. The rows do
/// not depend on each other, so the core overlaps their tests.
#[inline]
pub fn intersect_wide(node: &WideNode, o: Vec3, inv_d: Vec3, t_max: f32) -> ([f32; WIDTH], u32) {
    let mut t_enter = [0.0; WIDTH];
    let mut entered = 0;
    for h in 0..ROWS {
        let (t_near, mask) = intersect_boxes4(
            [node.min_x[h], node.min_y[h], node.min_z[h]],
            [node.max_x[h], node.max_y[h], node.max_z[h]],
            o,
            inv_d,
            t_max,
        );
        entered |= mask << (4 * h);
        t_enter[4 * h..4 * h + 4].copy_from_slice(&t_near.to_array());
    }
    let mut occupied = 0;
    for (c, &count) in node.count.iter().enumerate() {
        occupied |= u32::from(count != EMPTY_SLOT) << c;
    }
    (t_enter, entered & occupied)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::Traversal;
    use crate::layout::Triangle;

    /// The leaves under four-wide node `index`, depth first in slot order, as (first entry,
    /// count, box).
    fn leaves4(nodes: &[BvhNode], index: usize, out: &mut Vec<(u32, u32, Vec3, Vec3)>) {
        for s in slots(&nodes[index]) {
            if s.count == 0 {
                leaves4(nodes, s.child as usize, out);
            } else {
                out.push((s.child, s.count, s.lo, s.hi));
            }
        }
    }

    /// The same for the wide tree; also checks that every interior slot's box holds the boxes
    /// of all the leaves under it.
    fn leaves8(wide: &[WideNode], index: usize, out: &mut Vec<(u32, u32, Vec3, Vec3)>) {
        let node = &wide[index];
        for c in (0..WIDTH).filter(|&c| node.count[c] != EMPTY_SLOT) {
            let (lo, hi) = node.child_bounds(c);
            if node.count[c] == 0 {
                let from = out.len();
                leaves8(wide, node.child[c] as usize, out);
                for &(_, _, a, b) in &out[from..] {
                    assert!(
                        lo.cmple(a).all() && b.cmple(hi).all(),
                        "a slot's box is too small"
                    );
                }
            } else {
                out.push((node.child[c], node.count[c], lo, hi));
            }
        }
    }

    /// Whether the wide tree has exactly the four-wide tree's leaves, boxes and order.
    fn same_leaves(nodes: &[BvhNode], wide: &[WideNode]) -> bool {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        leaves4(nodes, 0, &mut a);
        leaves8(wide, 0, &mut b);
        a == b
    }

    fn soup(n: u32) -> Vec<Triangle> {
        let r = |i: u32, k: u32| {
            crate::math::sampling::u32_to_unit_f32(crate::math::sampling::pcg4d([i, k, 5, 6])[0])
                * 20.0
        };
        (0..n)
            .map(|i| {
                let c = Vec3::new(r(i, 0), r(i, 1), r(i, 2));
                let v = |k| (c + Vec3::new(r(i, k), r(i, k + 1), r(i, k + 2)) * 0.05).into();
                Triangle::new(v(3), v(6), v(9), 0)
            })
            .collect()
    }

    #[test]
    fn the_wide_tree_keeps_every_leaf_its_box_and_its_order() {
        for n in [1, 3, 5, 17, 300, 5000] {
            let (nodes, _, wide) = crate::accel::bvh::build_trees(&soup(n), &[], Traversal::Cpu);
            assert!(same_leaves(&nodes, &wide), "{n} triangles");
        }
    }

    #[test]
    fn the_wide_tree_has_fewer_levels_than_the_four_wide_one() {
        let (nodes, _, wide) = crate::accel::bvh::build_trees(&soup(5000), &[], Traversal::Cpu);
        assert!(
            wide.len() * 3 < nodes.len() * 2,
            "{} wide nodes for {} four-wide ones",
            wide.len(),
            nodes.len()
        );
    }

    #[test]
    fn one_for_one_keeps_every_node_as_it_is() {
        let (nodes, _) = crate::accel::bvh::build(&soup(300), &[], Traversal::Cpu);
        let wide = one_for_one(&nodes);
        assert_eq!(wide.len(), nodes.len());
        assert!(same_leaves(&nodes, &wide));
        assert!(wide
            .iter()
            .all(|n| n.count[4..].iter().all(|&c| c == EMPTY_SLOT)));
    }

    /// The check above fails when a slot goes missing: it can tell a broken collapse.
    #[test]
    fn a_dropped_slot_is_caught() {
        let (nodes, _, mut wide) = crate::accel::bvh::build_trees(&soup(300), &[], Traversal::Cpu);
        let last = wide.len() - 1;
        let c = (0..WIDTH)
            .rev()
            .find(|&c| wide[last].count[c] != EMPTY_SLOT)
            .unwrap();
        wide[last].count[c] = EMPTY_SLOT;
        assert!(!same_leaves(&nodes, &wide));
    }

    /// The wide slab test gives, slot by slot, what the slab test of that slot's box alone gives
    /// (written out per box here, the same f32 operations): the same entry distance to the bit
    /// and the same verdict, occupied slots only, in the slot's bit of the mask.
    #[test]
    fn the_wide_slab_test_is_the_slab_test_of_each_slot() {
        let (_, _, wide) = crate::accel::bvh::build_trees(&soup(2000), &[], Traversal::Cpu);
        let node = &wide[0];
        for i in 0..1000u32 {
            let r = |k| {
                crate::math::sampling::u32_to_unit_f32(
                    crate::math::sampling::pcg4d([i, k, 7, 8])[0],
                )
            };
            let o = Vec3::new(r(0), r(1), r(2)) * 30.0 - 5.0;
            let d = (Vec3::new(r(3), r(4), r(5)) - 0.5).normalize();
            let inv_d = crate::math::geometry::safe_inverse(d);
            let t_max = r(6) * 40.0;
            let (t_enter, mask) = intersect_wide(node, o, inv_d, t_max);
            for (c, &t) in t_enter.iter().enumerate() {
                let (lo, hi) = node.child_bounds(c);
                let (t_lo, t_hi) = ((lo - o) * inv_d, (hi - o) * inv_d);
                let near = t_lo.min(t_hi);
                let far = t_lo.max(t_hi);
                let t_near = near.x.max(near.y).max(near.z).max(0.0);
                let t_far =
                    far.x.min(far.y).min(far.z) * (1.0 + 2.0 * crate::math::geometry::gamma(3));
                let enters = node.count[c] != EMPTY_SLOT && t_near <= t_far.min(t_max);
                assert_eq!(mask >> c & 1 == 1, enters, "ray {i}, slot {c}");
                if enters {
                    assert_eq!(t.to_bits(), t_near.to_bits(), "ray {i}, slot {c}");
                }
            }
        }
    }
}
