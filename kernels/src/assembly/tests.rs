use super::*;

/// A band of 4-slot elements (two consecutive pairs of unknowns each), long enough for
/// several chunks per group.
fn band(n_el: usize) -> (Connectivity, usize) {
    let mut conn = Connectivity::new();
    for e in 0..n_el {
        let d = 2 * e as u32;
        conn.push(&[d, d + 1, d + 2, d + 3]);
    }
    (conn, 2 * n_el + 2)
}

#[test]
fn chunks_of_one_colour_share_no_unknown() {
    let (conn, n) = band(5 * ELEM_CHUNK + 17);
    let plan = AssemblyPlan::with_groups(n, &conn, &[3 * ELEM_CHUNK, conn.len()]);
    assert_eq!(plan.n_groups(), 2);
    for g in 0..2 {
        assert!(
            plan.n_colours(g) >= 2,
            "consecutive chunks share an unknown"
        );
    }
    for k in 0..plan.group_colour[2] {
        let mut owner = vec![u32::MAX; n];
        for &c in &plan.colour_chunks[plan.colour_ptr[k]..plan.colour_ptr[k + 1]] {
            for e in plan.chunk_start[c as usize]..plan.chunk_start[c as usize + 1] {
                for &d in conn.dofs(e) {
                    let o = &mut owner[d as usize];
                    assert!(*o == u32::MAX || *o == c, "colour {k}: chunks {o} and {c}");
                    *o = c;
                }
            }
        }
    }
    // colours run group by group, and every chunk has one
    for (c, &k) in plan.chunk_colour.iter().enumerate() {
        let g = plan
            .group_start
            .partition_point(|&s| s <= plan.chunk_start[c])
            - 1;
        assert!((plan.group_colour[g]..plan.group_colour[g + 1]).contains(&(k as usize)));
    }
    // every element of this band is paired: 2 row lengths and 4 blocks
    assert_eq!(plan.n_paired(0) + plan.n_paired(1), conn.len());
    assert_eq!(plan.map_len(0), 3 * ELEM_CHUNK * 6);
}

#[test]
fn general_index_follows_the_pair_order() {
    for m in 1..8 {
        for_pairs(m, |k, a, b| {
            assert_eq!(general_index(m, a, b), k, "m {m} ({a}, {b})")
        });
    }
}
