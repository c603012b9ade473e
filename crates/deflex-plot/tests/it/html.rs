use crate::sine_series;
use deflex_plot::{FileLink, HtmlReport, PlotError, PlotSpec, html_escape, inline_html, line_plot};
use std::path::Path;

/// The loader of a page without images: never called.
fn no_images(path: &Path) -> std::io::Result<Vec<u8>> {
    panic!("a page without images asked for {}", path.display())
}

#[test]
fn escapes_all_special_characters() {
    assert_eq!(
        html_escape(r#"<a href="x">Tom & 'Jerry'</a>"#),
        "&lt;a href=&quot;x&quot;&gt;Tom &amp; &#39;Jerry&#39;&lt;/a&gt;"
    );
    assert_eq!(
        html_escape("plain ünïcode ±0.1 mm"),
        "plain ünïcode ±0.1 mm"
    );
}

#[test]
fn report_text_is_escaped_everywhere() {
    let mut r = HtmlReport::new("T <1>");
    r.section("S & S")
        .paragraph("<script>alert(1)</script>")
        .note("SIMULATED <b>")
        .preformatted("a<b")
        .table(&["<h>"], &[vec!["<c>".to_string()]]);
    let html = r.render(no_images).unwrap();
    assert!(!html.contains("<script>"));
    assert!(html.contains("<title>T &lt;1&gt;</title>"));
    assert!(html.contains("<h2 id=\"s-s\">S &amp; S</h2>"));
    assert!(html.contains("&lt;script&gt;alert(1)&lt;/script&gt;"));
    assert!(html.contains("<div class=\"note\">SIMULATED &lt;b&gt;</div>"));
    assert!(html.contains("<th>&lt;h&gt;</th>"));
    assert!(html.contains("<td>&lt;c&gt;</td>"));
    assert!(html.contains("<pre>a&lt;b</pre>"));
}

#[test]
fn table_cells_and_alignment() {
    let mut r = HtmlReport::new("t");
    r.table(
        &["axis", "RMSE [mm]"],
        &[
            vec!["x".into(), "0.125".into()],
            vec!["norm".into(), "-1e-3".into()],
        ],
    );
    let html = r.render(no_images).unwrap();
    assert!(html.contains("<td>x</td><td class=\"num\">0.125</td>"));
    assert!(html.contains("<td class=\"num\">-1e-3</td>"));
}

#[test]
fn ragged_table_is_an_error() {
    let mut r = HtmlReport::new("t");
    r.table(&["a", "b"], &[vec!["1".into()]]);
    let e = r.render(no_images).unwrap_err();
    assert!(matches!(e, PlotError::InvalidInput { .. }), "{e}");
    assert!(e.to_string().contains("row 0 has 1 cells"), "{e}");
}

/// The loader's failure is an I/O error naming the image (deflex-app's `report::draw` checks
/// the same with a file that does not exist); an image of a format the page cannot embed is
/// refused before its bytes are asked for.
#[test]
fn missing_image_error_names_the_file() {
    let mut r = HtmlReport::new("t");
    r.image("/nonexistent/deflex/fig.png", "c");
    let e = r
        .render(|_| Err(std::io::Error::from(std::io::ErrorKind::NotFound)))
        .unwrap_err();
    assert!(matches!(e, PlotError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/deflex/fig.png"), "{e}");
    let mut r = HtmlReport::new("t");
    r.image("fig.bmp", "c");
    assert!(matches!(
        r.render(no_images).unwrap_err(),
        PlotError::UnsupportedFormat { .. }
    ));
}

#[test]
fn backticks_become_code_after_escaping() {
    assert_eq!(
        inline_html("run `deflex plot <log>` & look"),
        "run <code>deflex plot &lt;log&gt;</code> &amp; look"
    );
    assert_eq!(
        inline_html("`a` and `b`"),
        "<code>a</code> and <code>b</code>"
    );
    // An unpaired backtick is kept as a character.
    assert_eq!(inline_html("`a` it`s"), "<code>a</code> it`s");
    assert_eq!(inline_html("no code"), "no code");
    // Everywhere the page prints text: no literal backtick is left.
    let png = Path::new("f.png");
    let mut r = HtmlReport::new("The `x` report");
    r.contents()
        .section("About `deflex plot`")
        .subsection("The `log`")
        .paragraph("Written by `deflex run`.")
        .note("SIMULATED by `deflex sim`")
        .table(&["`col`"], &[vec!["`cell`".into()]])
        .files(&[FileLink::new("a.csv", "columns `x_m`, `y_m`")])
        .image(png, "drawn by `line_plot`");
    let html = r.render(|_| Ok(b"\x89PNG\r\n\x1a\n".to_vec())).unwrap();
    let body = &html[html.find("<body>").unwrap()..];
    assert!(!body.contains('`'), "{body}");
    for code in [
        "x",
        "deflex plot",
        "log",
        "deflex run",
        "deflex sim",
        "col",
        "cell",
        "x_m",
    ] {
        assert!(
            body.contains(&format!("<code>{code}</code>")),
            "{code}: {body}"
        );
    }
    assert!(body.contains("alt=\"drawn by line_plot\""), "{body}");
    assert!(body.contains("<figcaption>drawn by <code>line_plot</code></figcaption>"));
}

/// At 700 px nothing but a table's own wrapper scrolls sideways: every table sits in a
/// `div.table-wrap` that scrolls on its own, images shrink to the column, long words wrap.
#[test]
fn tables_scroll_in_their_own_wrapper_and_images_fit() {
    let mut r = HtmlReport::new("t");
    r.table(&["a"], &[vec!["1".into()]])
        .paragraph("between")
        .table(&["b", "c"], &[vec!["x".into(), "y".into()]]);
    let html = r.render(no_images).unwrap();
    let tables = html.matches("<table>").count();
    assert_eq!(tables, 2);
    assert_eq!(
        html.matches("<div class=\"table-wrap\"><table>").count(),
        tables
    );
    assert_eq!(html.matches("</table></div>").count(), tables);
    let css = &html[html.find("<style>").unwrap()..html.find("</style>").unwrap()];
    assert!(
        css.contains("div.table-wrap{overflow-x:auto;max-width:100%"),
        "{css}"
    );
    assert!(css.contains("img{max-width:100%;height:auto}"), "{css}");
    let body_rule = &css[css.find("body{").unwrap()..];
    let body_rule = &body_rule[..body_rule.find('}').unwrap()];
    assert!(body_rule.contains("overflow-wrap:anywhere"), "{body_rule}");
    // No fixed width wider than 700 px anywhere in the page's style.
    for (i, _) in css.match_indices("width:") {
        let value: String = css[i + 6..]
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect();
        if let Ok(px) = value.parse::<u32>() {
            assert!(
                px <= 700 || css[..i].ends_with("max-"),
                "fixed width {px} px in {css}"
            );
        }
    }
}

#[test]
fn html_report_embeds_png_as_data_uri() {
    let png = Path::new("fig.png");
    let bytes = line_plot(
        png,
        &PlotSpec::new("Fig", "x", "y").size(300, 200),
        &sine_series(),
    )
    .unwrap()
    .into_bytes();
    let mut r = HtmlReport::new("Report & co");
    r.note("SIMULATED")
        .section("Plots")
        .paragraph("See below.")
        .image(png, "Figure 1: <sine>");
    let html = r
        .render(|path| {
            assert_eq!(path, png);
            Ok(bytes.clone())
        })
        .unwrap();
    let uri = format!(
        "data:image/png;base64,{}",
        data_encoding::BASE64.encode(&bytes)
    );
    assert!(html.contains(&uri), "whole PNG embedded");
    assert!(
        html.contains("data:image/png;base64,iVBORw0KGgo"),
        "PNG magic in base64"
    );
    assert!(html.contains("<figcaption>Figure 1: &lt;sine&gt;</figcaption>"));
    assert!(html.contains("<title>Report &amp; co</title>"));
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "no network"
    );
}

#[test]
fn html_contents_and_file_links() {
    let mut r = HtmlReport::new("t");
    r.contents()
        .section("1. Plan & campaign")
        .subsection("Points")
        .section("Data files")
        .files(&[
            FileLink::new("plan.csv", "the plan <rows>"),
            FileLink::new("forming_open/log.csv", "the log"),
        ])
        .section("Data files");
    let html = r.render(no_images).unwrap();
    assert!(html.contains("<h2 id=\"1-plan-campaign\">1. Plan &amp; campaign</h2>"));
    assert!(html.contains("<h3 id=\"points\">Points</h3>"));
    assert!(html.contains("<h2 id=\"data-files-2\">"), "unique ids");
    assert!(html.contains("<a href=\"#1-plan-campaign\">1. Plan &amp; campaign</a>"));
    assert!(html.contains("<a href=\"#points\">"));
    assert!(html.contains("<a href=\"#data-files-2\">"));
    assert!(html.contains("<a href=\"plan.csv\"><code>plan.csv</code></a>: the plan &lt;rows&gt;"));
    assert!(html.contains("<a href=\"forming_open/log.csv\">"));
    for bad in [
        "/etc/passwd",
        "../x.csv",
        "a/../../x.csv",
        "http://x/y.csv",
        "javascript:alert(1)",
        "a b.csv",
        "",
    ] {
        let mut r = HtmlReport::new("t");
        r.files(&[FileLink::new(bad, "d")]);
        assert!(r.render(no_images).is_err(), "{bad:?} accepted");
    }
}
