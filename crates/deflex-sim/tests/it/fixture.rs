//! The stiff fixture's elastic contact.

use deflex_sim::fixture::Fixture;
use nalgebra::Vector3;

#[test]
fn elastic_contact_below_the_surface_only() {
    let f = Fixture::new(1e7, 0.0075);
    assert_eq!(f.contact(&Vector3::new(0.0, 0.0, 0.001)).force_n, 0.0);
    let c = f.contact(&Vector3::new(0.01, 0.0, -0.0002));
    assert!((c.force_n - 2000.0).abs() < 1e-9);
    assert!((c.penetration_m - 0.0002).abs() < 1e-15);
}
