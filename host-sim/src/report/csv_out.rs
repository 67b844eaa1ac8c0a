//! CSV time series.

use std::path::Path;

use anyhow::Context;

/// Writes a CSV file with a header row and numeric rows. Every row must have as many columns as
/// the header.
pub fn write_csv<I, R>(path: &Path, header: &[&str], rows: I) -> anyhow::Result<()>
where
    I: IntoIterator<Item = R>,
    R: AsRef<[f64]>,
{
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("creating {}", path.display()))?;
    w.write_record(header)?;
    for row in rows {
        let row = row.as_ref();
        anyhow::ensure!(
            row.len() == header.len(),
            "CSV row has {} columns, header {}",
            row.len(),
            header.len()
        );
        w.write_record(row.iter().map(|v| format!("{v:.9e}")))?;
    }
    w.flush()?;
    Ok(())
}
