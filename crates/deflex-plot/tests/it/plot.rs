use deflex_plot::{clip_segment, strokable_pieces};

#[test]
fn clipping_keeps_the_part_inside_the_rectangle() {
    let (xr, yr) = ((0.0, 10.0), (0.0, 1.0));
    // Crosses the bottom edge half-way, and a segment wholly below.
    assert_eq!(
        clip_segment((0.0, 1.0), (2.0, -1.0), xr, yr),
        Some((0.0, 0.5))
    );
    assert_eq!(clip_segment((0.0, -1.0), (2.0, -0.5), xr, yr), None);
    let pieces = strokable_pieces(
        &[(0.0, 0.5), (1.0, 0.5), (2.0, -1.0), (3.0, 0.5), (4.0, 0.5)],
        xr,
        yr,
        (1000, 100),
    );
    assert_eq!(pieces.len(), 2, "{pieces:?}");
    for p in &pieces {
        assert!(
            p.iter()
                .all(|&(x, y)| (0.0..=10.0).contains(&x) && (0.0..=1.0).contains(&y))
        );
    }
    assert!((pieces[0].last().unwrap().1).abs() < 1e-12, "{pieces:?}");
}

#[test]
fn sharp_turns_end_the_stroke_and_gentle_ones_do_not() {
    let (xr, yr) = ((0.0, 100.0), (0.0, 100.0));
    // A spike up and down one pixel apart: cut at its tip; a 45° bend: kept whole.
    let spike = strokable_pieces(
        &[(10.0, 0.0), (11.0, 90.0), (12.0, 0.0)],
        xr,
        yr,
        (100, 100),
    );
    assert_eq!(
        spike,
        vec![
            vec![(10.0, 0.0), (11.0, 90.0)],
            vec![(11.0, 90.0), (12.0, 0.0)]
        ]
    );
    let bend = strokable_pieces(&[(0.0, 0.0), (50.0, 0.0), (90.0, 40.0)], xr, yr, (100, 100));
    assert_eq!(bend.len(), 1);
    assert_eq!(bend[0].len(), 3);
}
