//! Which free blocks have no chain of contacts down to a fixed block: in a static analysis
//! they float, and the stiffness matrix is singular.

use crate::mesh::{BlockDofs, Mesh};

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Free blocks (indices, ascending) not connected through contacts to any fixed block.
pub fn unsupported_blocks(mesh: &Mesh) -> Vec<usize> {
    let n = mesh.blocks.len();
    let mut parent: Vec<usize> = (0..n).collect();
    for c in &mesh.contacts {
        let (a, b) = (
            find(&mut parent, c.block_l as usize),
            find(&mut parent, c.block_m as usize),
        );
        if a != b {
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut grounded = vec![false; n];
    for (i, b) in mesh.blocks.iter().enumerate() {
        if b.dofs == BlockDofs::Fixed {
            let r = find(&mut parent, i);
            grounded[r] = true;
        }
    }
    (0..n)
        .filter(|&i| mesh.blocks[i].dofs != BlockDofs::Fixed && !grounded[find(&mut parent, i)])
        .collect()
}
