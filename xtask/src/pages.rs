//! The generated documentation pages (`docs/validation.md`,
//! `docs/performance.md`): what the tasks that measure write into them.
//!
//! A page is rebuilt whole from its template on every run, but the results
//! it shows are kept per *slot*: a block between
//! `<!-- result KEY SLOT k=v … -->` and `<!-- /result -->` (a validation
//! case, a bench section; `SLOT` is `full`, `quick` or `any`). A run
//! replaces the blocks of what it measured and carries the others over from
//! the page as it was, so a filtered run or a quick run never erases a full
//! run's results, and a diff after a run shows only the dates and the
//! numbers it measured. Everything else on a page comes from code, in a
//! fixed order and format.
//!
//! Not for the Markdown of the results themselves: each task formats its
//! own tables.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

const END: &str = "<!-- /result -->";

/// One kept result: its marker's attributes and its body.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// `k=v` pairs of the marker, in order.
    pub attrs: Vec<(String, String)>,
    /// The Markdown between the markers, without surrounding blank lines.
    pub body: String,
}

impl Block {
    /// The value of the attribute `key`.
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// The blocks of a page by (key, slot). Text outside blocks is dropped: the
/// page's template rebuilds it.
pub fn blocks(page: &str) -> BTreeMap<(String, String), Block> {
    let mut out = BTreeMap::new();
    let mut rest = page;
    while let Some(start) = rest.find("<!-- result ") {
        let after = &rest[start + "<!-- result ".len()..];
        let Some(close) = after.find("-->") else {
            break;
        };
        let mut words = after[..close].split_whitespace();
        let (Some(key), Some(slot)) = (words.next(), words.next()) else {
            rest = &after[close..];
            continue;
        };
        let attrs = words
            .filter_map(|w| w.split_once('='))
            .map(|(k, v)| (k.to_owned(), v.to_owned()))
            .collect();
        let body_and_rest = &after[close + 3..];
        let Some(end) = body_and_rest.find(END) else {
            break;
        };
        out.insert(
            (key.to_owned(), slot.to_owned()),
            Block {
                attrs,
                body: body_and_rest[..end].trim().to_owned(),
            },
        );
        rest = &body_and_rest[end + END.len()..];
    }
    out
}

/// A block as it stands on a page.
pub fn render(key: &str, slot: &str, block: &Block) -> String {
    let mut out = format!("<!-- result {key} {slot}");
    for (k, v) in &block.attrs {
        let _ = write!(out, " {k}={v}");
    }
    let _ = write!(out, " -->\n\n{}\n\n{END}\n", block.body);
    out
}

/// The blocks of the page at `path` (none when it does not exist yet).
pub fn read(path: &Path) -> BTreeMap<(String, String), Block> {
    std::fs::read_to_string(path)
        .map(|text| blocks(&text))
        .unwrap_or_default()
}

/// Writes a page whole or not at all.
pub fn write(path: &Path, text: &str) -> Result<(), String> {
    drape_io::atomic::write(path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}

/// Today's date in UTC, `YYYY-MM-DD` (std has no calendar: days since the
/// epoch to a civil date, H. Hinnant's algorithm).
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    civil_date(secs / 86_400)
}

fn civil_date(days: u64) -> String {
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// The machine a measurement ran on, in one line: CPU model, hardware
/// threads, memory and the load average.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.split_whitespace().collect::<Vec<_>>().join(" "))
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    let threads = std::thread::available_parallelism().map_or(0, usize::from);
    let memory = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map(|kb| format!(", {:.0} GiB", kb / 1_048_576.0))
        .unwrap_or_default();
    let load = std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".to_owned());
    format!(
        "{cpu}, {threads} hardware threads{memory}, {} (load average {load})",
        std::env::consts::OS
    )
}

/// Says on standard error when a quick run's result sits beside a full
/// run's of the same thing, so that a developer reading the page knows
/// which is which.
pub fn note_quick_beside_full(page: &Path, key: &str, kept: &BTreeMap<(String, String), Block>) {
    if let Some(full) = kept.get(&(key.to_owned(), "full".to_owned())) {
        eprintln!(
            "{}: `{key}`: this quick run's result is shown beside the full run's of {} (kept)",
            page.display(),
            full.attr("date").unwrap_or("an earlier date")
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_round_trip_and_text_outside_them_is_dropped() {
        let a = Block {
            attrs: vec![
                ("date".into(), "2026-11-28".into()),
                ("passed".into(), "3".into()),
            ],
            body: "| a | b |\n|---|---|".into(),
        };
        let b = Block {
            attrs: vec![],
            body: "text".into(),
        };
        let page = format!(
            "# Page\n\nprose\n\n{}\nmore prose\n\n{}",
            render("x/y", "full", &a),
            render("x/y", "quick", &b)
        );
        let read = blocks(&page);
        assert_eq!(read.len(), 2);
        assert_eq!(read[&("x/y".into(), "full".into())], a);
        assert_eq!(read[&("x/y".into(), "quick".into())], b);
        assert_eq!(a.attr("passed"), Some("3"));
        // Rendering what was read gives the same text.
        assert_eq!(
            render("x/y", "full", &read[&("x/y".into(), "full".into())]),
            render("x/y", "full", &a)
        );
    }

    #[test]
    fn civil_dates() {
        assert_eq!(civil_date(0), "1970-01-01");
        assert_eq!(civil_date(11_016), "2000-02-29");
        assert_eq!(civil_date(20_785), "2026-11-28");
    }
}
