//! The cache-statistics rows of [`crate::replay`] as text: CSV at full precision and an
//! aligned table (what `oslf cache-stats` writes and prints).

use std::fmt::Write as _;

use crate::replay::Row;

/// The CSV columns, in [`Row`] field order.
pub const CSV_HEADER: &str = "mode,blend,granularity,size,slots,path,phase,first_frame,\
last_frame,frames,requests,hits,misses,miss_rate,loads,evictions,over_budget,ram_hits,\
faces_decoded,bytes_decoded,bytes_uploaded,decode_ms,upload_ms,cache_ms,frame_ms,passes";

/// The rows as CSV with [`CSV_HEADER`]; numbers at full precision (they parse back to the
/// same values as the JSON's).
pub fn to_csv(rows: &[Row]) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.mode,
            r.blend,
            r.granularity,
            r.size,
            r.slots,
            r.path,
            r.phase,
            r.first_frame,
            r.last_frame,
            r.frames,
            r.requests,
            r.hits,
            r.misses,
            r.miss_rate,
            r.loads,
            r.evictions,
            r.over_budget,
            r.ram_hits,
            r.faces_decoded,
            r.bytes_decoded,
            r.bytes_uploaded,
            r.decode_ms,
            r.upload_ms,
            r.cache_ms,
            r.frame_ms,
            r.passes
        );
    }
    out
}

/// The table's column headings.
pub const TABLE_HEADER: [&str; 17] = [
    "mode",
    "blend",
    "unit",
    "slots",
    "path",
    "phase",
    "frames",
    "requests",
    "hits",
    "misses",
    "miss %",
    "loads",
    "evicted",
    "over",
    "MB decoded",
    "decode ms",
    "frame ms",
];

/// The cells of a row in the table: counts exact, miss rate in % to two decimals, MB to three,
/// milliseconds to one.
pub fn table_cells(r: &Row) -> [String; 17] {
    let slots = if r.size == r.slots.to_string() {
        r.size.clone()
    } else {
        format!("{} ({})", r.slots, r.size)
    };
    [
        r.mode.clone(),
        r.blend.clone(),
        r.granularity.clone(),
        slots,
        r.path.clone(),
        r.phase.clone(),
        r.frames.to_string(),
        r.requests.to_string(),
        r.hits.to_string(),
        r.misses.to_string(),
        format!("{:.2}", 100.0 * r.miss_rate),
        r.loads.to_string(),
        r.evictions.to_string(),
        r.over_budget.to_string(),
        format!("{:.3}", r.bytes_decoded as f64 / 1e6),
        format!("{:.1}", r.decode_ms),
        format!("{:.1}", r.frame_ms),
    ]
}

/// An aligned text table (text columns left-aligned, numbers right-aligned), a blank line
/// between (mode, blend) groups.
pub fn format_table(rows: &[Row]) -> String {
    let cells: Vec<[String; 17]> = rows.iter().map(table_cells).collect();
    let mut width = TABLE_HEADER.map(|h| h.chars().count());
    for c in &cells {
        for (w, s) in width.iter_mut().zip(c) {
            *w = (*w).max(s.chars().count());
        }
    }
    const TEXT: usize = 6; // mode, blend, unit, slots, path, phase
    let line = |out: &mut String, c: &[&str]| {
        let parts: Vec<String> = c
            .iter()
            .zip(width)
            .enumerate()
            .map(|(i, (s, w))| {
                let pad = w.saturating_sub(s.chars().count());
                if i < TEXT {
                    format!("{s}{}", " ".repeat(pad))
                } else {
                    format!("{}{s}", " ".repeat(pad))
                }
            })
            .collect();
        let _ = writeln!(out, "{}", parts.join("  ").trim_end());
    };
    let mut out = String::new();
    line(&mut out, &TABLE_HEADER);
    let mut group: Option<(&str, &str)> = None;
    for (r, c) in rows.iter().zip(&cells) {
        let g = (r.mode.as_str(), r.blend.as_str());
        if group.is_some_and(|p| p != g) {
            out.push('\n');
        }
        group = Some(g);
        let c: Vec<&str> = c.iter().map(String::as_str).collect();
        line(&mut out, &c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::replay::rows;

    #[test]
    fn csv_and_table_carry_the_rows_numbers() {
        let (path, replay, key) = crate::replay::tests::four_frame_orbit();
        let rows = rows(&key, &path, &replay);
        let csv = to_csv(&rows);
        assert_eq!(csv.lines().count(), 4);
        assert!(csv.contains("mirror,n,face,25%,30,orbit,all,1,4,4,44,31,13,"));
        let table = format_table(&rows);
        assert!(
            table.contains("30 (25%)") && table.contains("29.55"),
            "{table}"
        );
    }
}
