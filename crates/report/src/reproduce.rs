//! The page of `limpid reproduce --report`: one table per paper (the paper's
//! number, limpid's, the difference, the note) and the findings.

use limpid_analysis::result::reproduction::{citation, sig, Reproduction};

use crate::svg::escape;
use crate::STYLE;

/// A self-contained HTML page of a reproduction.
pub fn reproduction_page(r: &Reproduction, title: &str) -> String {
    let mut s = format!(
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0}</title><style>{STYLE}</style></head><body><h1>{0}</h1>",
        escape(title)
    );
    s.push_str("<h2>Findings</h2><ul>");
    for f in &r.findings {
        let (class, word) = if f.holds {
            ("ok", "holds")
        } else {
            ("bad", "differs")
        };
        s.push_str(&format!(
            "<li><span class=\"{class}\">{word}</span> {}: {} — {}</li>",
            escape(citation(&f.seed)),
            escape(&f.claim),
            escape(&f.evidence)
        ));
    }
    s.push_str("</ul>");
    let mut seed = String::new();
    for x in &r.rows {
        if x.seed != seed {
            if !seed.is_empty() {
                s.push_str("</tbody></table>");
            }
            seed.clone_from(&x.seed);
            s.push_str(&format!(
                "<h2>{}</h2><table><thead><tr><th>item</th><th>paper</th><th>limpid</th><th>difference</th><th>unit</th><th>note</th></tr></thead><tbody>",
                escape(citation(&seed))
            ));
        }
        let cell = |v: Option<f64>| v.map_or("–".to_string(), sig);
        let diff = x.difference();
        s.push_str(&format!(
            "<tr><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td>{}</td><td>{}</td></tr>",
            escape(&x.item),
            cell(x.paper),
            cell(x.limpid),
            diff,
            escape(&x.unit),
            escape(&x.note)
        ));
    }
    if !seed.is_empty() {
        s.push_str("</tbody></table>");
    }
    s.push_str("</body></html>\n");
    s
}
