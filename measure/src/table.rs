//! Tables of results as aligned text (the terminal), Markdown (docs/measurements.md) and CSV.

use std::fmt::Write as _;

/// A titled table of text cells; numeric columns are right-aligned.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Table {
    pub title: String,
    pub headers: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new(title: &str, headers: &[&str]) -> Self {
        Self {
            title: title.to_string(),
            headers: headers.iter().map(|h| h.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row (missing cells are left empty, extra cells dropped).
    pub fn push(&mut self, cells: Vec<String>) {
        let mut cells = cells;
        cells.resize(self.headers.len(), String::new());
        self.rows.push(cells);
    }

    fn numeric(&self, column: usize) -> bool {
        !self.rows.is_empty()
            && self.rows.iter().all(|r| {
                let c = r[column].trim_end_matches(['×', '%', 'x']);
                c.is_empty() || c == "–" || c.parse::<f64>().is_ok()
            })
    }

    fn widths(&self) -> Vec<usize> {
        (0..self.headers.len())
            .map(|c| {
                self.rows
                    .iter()
                    .map(|r| r[c].chars().count())
                    .chain([self.headers[c].chars().count()])
                    .max()
                    .unwrap_or(0)
            })
            .collect()
    }

    /// Aligned plain text, title first.
    pub fn to_text(&self) -> String {
        let widths = self.widths();
        let mut out = format!("{}\n", self.title);
        let line = |cells: &[String], out: &mut String| {
            for (c, cell) in cells.iter().enumerate() {
                let pad = widths[c] - cell.chars().count();
                if c > 0 {
                    out.push_str("  ");
                }
                if self.numeric(c) {
                    out.push_str(&" ".repeat(pad));
                    out.push_str(cell);
                } else {
                    out.push_str(cell);
                    out.push_str(&" ".repeat(pad));
                }
            }
            out.push('\n');
        };
        line(&self.headers, &mut out);
        let rule: Vec<String> = widths.iter().map(|w| "-".repeat(*w)).collect();
        line(&rule, &mut out);
        for r in &self.rows {
            line(r, &mut out);
        }
        out
    }

    /// A GitHub Markdown table under a bold title.
    pub fn to_markdown(&self) -> String {
        let mut out = format!("**{}**\n\n| {} |\n|", self.title, self.headers.join(" | "));
        for c in 0..self.headers.len() {
            out.push_str(if self.numeric(c) { " ---: |" } else { " --- |" });
        }
        out.push('\n');
        for r in &self.rows {
            let _ = writeln!(out, "| {} |", r.join(" | "));
        }
        out
    }

    /// CSV with a header row (RFC 4180 quoting).
    pub fn to_csv(&self) -> String {
        let mut out = String::new();
        for r in std::iter::once(&self.headers).chain(&self.rows) {
            let cells: Vec<String> = r.iter().map(|c| csv_cell(c)).collect();
            let _ = writeln!(out, "{}", cells.join(","));
        }
        out
    }
}

/// One CSV field, quoted when it holds a comma, quote or line break.
pub fn csv_cell(c: &str) -> String {
    if c.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", c.replace('"', "\"\""))
    } else {
        c.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_markdown_and_csv_agree() {
        let mut t = Table::new("T", &["method", "error"]);
        t.push(vec!["a, b".into(), "0.125".into()]);
        t.push(vec!["c".into(), "12.5".into()]);
        let text = t.to_text();
        assert!(
            text.contains("a, b    0.125\n") && text.contains("c        12.5\n"),
            "{text}"
        );
        assert!(t
            .to_markdown()
            .contains("| method | error |\n| --- | ---: |\n| a, b | 0.125 |"));
        assert_eq!(t.to_csv(), "method,error\n\"a, b\",0.125\nc,12.5\n");
    }
}
