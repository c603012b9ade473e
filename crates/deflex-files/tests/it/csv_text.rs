//! CSV text in memory ([`deflex_files::csv_text`]).

use deflex_files::csv_text;

#[test]
fn csv_text_quotes_as_the_csv_writer_does() {
    let records: Vec<Vec<&str>> = vec![
        vec!["load_case", "label", "x_m"],
        vec!["a", "with, comma", "1.5"],
        vec!["b", "with \"quotes\"", "-0.0"],
        vec!["c", "two\nlines", ""],
        vec!["d", "carriage\rreturn", "1e-7"],
        vec!["#e", " spaced ", "µm"],
    ];
    let mut writer = csv::WriterBuilder::new().from_writer(Vec::new());
    for record in &records {
        writer.write_record(record).unwrap();
    }
    let expected = String::from_utf8(writer.into_inner().unwrap()).unwrap();
    assert_eq!(csv_text(&records), expected);
    assert_eq!(
        csv_text([["a", "with, comma"], ["b", "with \"quotes\""]]),
        "a,\"with, comma\"\nb,\"with \"\"quotes\"\"\"\n"
    );
}

#[test]
fn csv_text_writes_every_record_whatever_its_length() {
    // A lone empty field is quoted so that the line is not empty; records of another length
    // than the first are written as they are (nothing dropped or run together).
    assert_eq!(csv_text([vec![""]]), "\"\"\n");
    assert_eq!(csv_text(Vec::<Vec<String>>::new()), "");
    assert_eq!(
        csv_text([vec!["a", "b", "c"], vec!["1"], vec!["2", "3", "4", "5"]]),
        "a,b,c\n1\n2,3,4,5\n"
    );
}
