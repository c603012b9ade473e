//! CSV text built in memory, for the writers of deflex's CSV formats that return the text and
//! leave the writing of the file to their caller.

/// The CSV text of `records`, one line each (RFC 4180 quoting: a field holding a comma, a
/// quote or a line break is quoted, quotes doubled; `\n` line ends), as the `csv` crate writes
/// it.
///
/// Nothing here can fail, and the code says why instead of hiding an error behind a default:
/// the writer writes into a `Vec<u8>`, which takes every byte; it accepts records of any length
/// (`flexible`: a record of another length than the first is written as it is, not refused
/// half-written); and UTF-8 fields joined by ASCII commas, quotes and line ends are UTF-8.
///
/// ```
/// let text = deflex_files::csv_text([vec!["name", "x_m"], vec!["a, b", "1.5"]]);
/// assert_eq!(text, "name,x_m\n\"a, b\",1.5\n");
/// ```
pub fn csv_text<R, F>(records: impl IntoIterator<Item = R>) -> String
where
    R: IntoIterator<Item = F>,
    F: AsRef<str>,
{
    let mut writer = csv::WriterBuilder::new()
        .flexible(true)
        .from_writer(Vec::new());
    for record in records {
        for field in record {
            writer
                .write_field(field.as_ref())
                .expect("a CSV writer into memory takes every field");
        }
        writer
            .write_record(None::<&[u8]>)
            .expect("a flexible CSV writer into memory ends every record");
    }
    let bytes = writer
        .into_inner()
        .expect("flushing a CSV writer into memory does not fail");
    String::from_utf8(bytes).expect("UTF-8 fields joined by ASCII separators are UTF-8")
}
