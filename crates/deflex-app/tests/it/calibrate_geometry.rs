//! The elasto-geometric calibration engine ([`deflex_app::calibrate_geometry`]): steps and losses parsed with
//! the CLI's messages.

use deflex_app::calibrate_geometry::*;
use deflex_calibrate::geometry::fit::Step;
use deflex_calibrate::geometry::solve::Loss;

#[test]
fn steps_and_losses_are_parsed_with_the_cli_messages() {
    let steps = parse_steps(&["registration".into(), "harmonics:2".into()]).unwrap();
    assert_eq!(steps, vec![Step::Registration, Step::Harmonics(2)]);
    let e = parse_steps(&["harmonics:9".into()]).unwrap_err();
    assert!(e.to_string().starts_with("steps: unknown step"), "{e}");
    assert!(matches!(parse_loss("cauchy:2").unwrap(), Loss::Cauchy(k) if k == 2.0));
    let e = parse_loss("l1").unwrap_err();
    assert_eq!(
        e.to_string(),
        "loss: expected huber, cauchy or none, got \"l1\""
    );
}
