//! 3-D deviation clouds ([`deflex_plot::cloud_3d`]).

use crate::{png_dims, svg_text};
use deflex_plot::{Cloud3, Plot3Spec, cloud_3d};
use std::path::Path;

#[test]
fn cloud_3d_renders_png_and_svg() {
    let pts: Vec<[f64; 3]> = (0..200)
        .map(|i| {
            let t = i as f64 * 0.1;
            [t.cos(), t.sin(), t * 0.05]
        })
        .collect();
    let spec = Plot3Spec::new("Deviation", "dx [mm]", "dy [mm]", "dz [mm]").size(640, 560);
    let clouds = [
        Cloud3::new("spiral", pts),
        Cloud3::new("origin", vec![[0.0; 3]]),
    ];
    let png = Path::new("c.png");
    assert_eq!(
        png_dims(&cloud_3d(png, &spec, &clouds).unwrap()),
        (640, 560)
    );
    let text = svg_text(cloud_3d(Path::new("c.svg"), &spec, &clouds).unwrap());
    for t in ["Deviation", "dx [mm]", "dy [mm]", "dz [mm]", "spiral"] {
        assert!(text.contains(t), "SVG lacks {t:?}");
    }
    assert!(cloud_3d(png, &spec, &[]).is_err());
    assert!(cloud_3d(png, &spec, &[Cloud3::new("e", vec![])]).is_err());
    assert!(cloud_3d(png, &spec, &[Cloud3::new("n", vec![[f64::NAN; 3]])]).is_err());
}
