use crate::{count, png_dims, png_pixels, svg_text};
use deflex_plot::{Lane, PlotSpec, palette_color, timeline_plot};
use std::path::Path;

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

#[test]
fn timeline_draws_lanes_and_checks_intervals() {
    let path = Path::new("t.png");
    let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
    let on: Vec<bool> = t.iter().map(|v| (2.0..6.0).contains(v)).collect();
    let lanes = [
        Lane::from_samples("active", &t, &on),
        Lane::new("fault (never)", vec![]),
        Lane::new("one cycle", vec![(5.0, 5.0)]).with_color((200, 0, 200)),
    ];
    let spec = PlotSpec::new("Controller state", "time [s]", "").size(800, 300);
    let image = timeline_plot(path, &spec, &lanes).unwrap();
    assert_eq!(png_dims(&image), (800, 300));
    let px = png_pixels(&image);
    assert!(count(&px, palette_color(0)) > 1000, "active bar drawn");
    assert!(
        count(&px, (200, 0, 200)) > 10,
        "a zero-length interval stays visible"
    );
    let text = svg_text(timeline_plot(Path::new("t.svg"), &spec, &lanes).unwrap());
    assert!(text.contains("fault (never)") && text.contains("time [s]"));
    assert!(timeline_plot(path, &spec, &[]).is_err());
    let bad = [Lane::new("b", vec![(2.0, 1.0)])];
    assert!(timeline_plot(path, &spec, &bad).is_err());
    let empty = [Lane::new("e", vec![])];
    assert!(timeline_plot(path, &spec, &empty).is_err());
    assert!(timeline_plot(path, &spec.clone().x_range(0.0, 1.0), &empty).is_ok());
}
