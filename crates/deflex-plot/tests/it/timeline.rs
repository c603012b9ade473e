use deflex_plot::Lane;

#[test]
fn samples_become_merged_intervals() {
    let t = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    let lane = Lane::from_samples("s", &t, &[false, true, true, false, true, true]);
    assert_eq!(lane.intervals, vec![(1.0, 3.0), (4.0, 6.0)]);
    assert_eq!(lane.duration(), 4.0);
    let never = Lane::from_samples("n", &t, &[false; 6]);
    assert!(never.intervals.is_empty());
    let always = Lane::from_samples("a", &t[..1], &[true]);
    assert_eq!(always.intervals, vec![(0.0, 0.0)]);
}
