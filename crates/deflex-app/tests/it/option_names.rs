//! One way to name an option in a workflow's messages ([`deflex_app::OptionNames`]): the
//! command line's flag (derived from the Python keyword, or from [`CLI_FLAGS`] where the flag
//! carries another unit) or Python's keyword, for every workflow both front ends call.

use deflex_app::OptionNames::{Cli, Python};
use deflex_app::option_names::CLI_FLAGS;
use deflex_app::twin::FormConflict;

#[test]
fn an_option_is_named_by_its_keyword_and_spelt_by_each_front_end() {
    assert_eq!(Cli.name("max_iterations"), "--max-iterations");
    for (keyword, flag) in CLI_FLAGS {
        assert_eq!(Cli.name(keyword), flag);
        assert_eq!(Python.name(keyword), keyword);
    }
    assert_eq!(Cli.name("seed_q"), "--seed-deg");
    assert_eq!(Cli.name("settings"), "--program-config");
    assert_eq!(Cli.switch("ignore_fk_check"), "--ignore-fk-check");
    assert_eq!(Python.switch("ignore_fk_check"), "ignore_fk_check=True");
    assert_eq!(
        Cli.context("data", "m.csv").as_deref(),
        Some("--data m.csv")
    );
    assert_eq!(Python.context("data", "m.csv"), None);
    assert_eq!(Cli.subject("setup"), "");
    assert_eq!(Python.subject("setup"), "setup: ");
}

/// The conflicts of a forming run's options, in each front end's words (the command line's as
/// its usage errors said them before the one mechanism).
#[test]
fn a_forming_runs_conflicts_name_the_options_of_the_front_end() {
    let cases = [
        (
            FormConflict::ModelWithoutCorrection,
            "--model: only used with --correction on",
            "model: only used with correction=\"on\"",
        ),
        (
            FormConflict::FixtureStiffnessWithoutPlunge,
            "--fixture-stiffness-n-m: applies to --path plunge",
            "fixture_stiffness_n_m: applies to path=\"plunge\"",
        ),
        (
            FormConflict::FeedWithGcode,
            "--feed-mm-s: applies to the built-in paths; a G-code file sets its own F",
            "feed_m_s: applies to the built-in paths; a G-code file sets its own F",
        ),
    ];
    for (conflict, cli, python) in cases {
        assert_eq!(conflict.describe(Cli), cli);
        assert_eq!(conflict.named(Python).to_string(), python);
        assert_eq!(
            conflict.named(Cli).kind(),
            deflex_app::ErrorKind::Input,
            "{cli}"
        );
    }
}
