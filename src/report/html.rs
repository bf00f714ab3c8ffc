//! The self-contained report page: charts inline as SVG, animations and error images as
//! base64 GIFs, a summary table, and a check script that marks the page when every image has
//! loaded (the browser test reads it).

use base64::Engine;

/// One run's row in the summary table.
pub struct Row {
    pub label: String,
    pub seconds: f64,
    pub rel_mse: f64,
    pub flip: f64,
    pub flicker: f64,
    /// Motion-compensated flicker F1.
    pub warped: f64,
    pub replaced: f64,
    pub acceptance: Option<f64>,
}

/// The reference's own noise: what a perfect renderer would measure.
pub struct FloorRow {
    pub label: String,
    pub rel_mse: f64,
    pub flicker: f64,
    pub warped: Option<f64>,
}

/// An animation (and its error animation) shown side by side.
pub struct Clip {
    pub label: String,
    pub gif: Vec<u8>,
    pub error_gif: Option<Vec<u8>>,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn gif_uri(bytes: &[u8]) -> String {
    format!(
        "data:image/gif;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

/// The page. `charts` are (title, SVG text); `notes` are lines of context (scene, adapter...);
/// `floor` is the last row of the table.
pub fn page(
    title: &str,
    notes: &[String],
    rows: &[Row],
    floor: Option<&FloorRow>,
    charts: &[(String, String)],
    clips: &[Clip],
) -> String {
    let mut h = String::new();
    h += "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
    h += &format!("<title>{}</title>\n", esc(title));
    h += "<style>body{font-family:sans-serif;margin:24px;color:#222;max-width:1600px}\
table{border-collapse:collapse;margin:12px 0}td,th{border:1px solid #bbb;padding:4px 10px;text-align:right}\
th{background:#eee}td:first-child{text-align:left}.charts{display:flex;flex-wrap:wrap;gap:12px}\
.charts figure{margin:0}.clips{display:flex;flex-wrap:wrap;gap:16px}.clip{text-align:center}\
.clip img{image-rendering:pixelated;width:256px;display:block;margin:2px}#check{color:#777;font-size:12px}</style>\n";
    h += "</head><body>\n";
    h += &format!("<h1>{}</h1>\n<ul>\n", esc(title));
    for n in notes {
        h += &format!("<li>{}</li>\n", esc(n));
    }
    h += "</ul>\n<h2>Summary</h2>\n<table><tr><th>run</th><th>s / frame</th><th>relMSE</th><th>FLIP</th><th>flicker F1</th><th>warped F1</th><th>VPLs replaced / frame</th><th>MH acceptance</th></tr>\n";
    for r in rows {
        h += &format!(
            "<tr><td>{}</td><td>{:.3}</td><td>{:.5}</td><td>{:.4}</td><td>{:.5}</td><td>{:.5}</td><td>{:.3}</td><td>{}</td></tr>\n",
            esc(&r.label),
            r.seconds,
            r.rel_mse,
            r.flip,
            r.flicker,
            r.warped,
            r.replaced,
            r.acceptance.map(|a| format!("{a:.3}")).unwrap_or_else(|| "-".into())
        );
    }
    if let Some(f) = floor {
        h += &format!(
            "<tr class=\"floor\"><td><i>{}</i></td><td>-</td><td><i>{:.5}</i></td><td>-</td><td><i>{:.5}</i></td><td><i>{}</i></td><td>-</td><td>-</td></tr>\n",
            esc(&f.label),
            f.rel_mse,
            f.flicker,
            f.warped.map(|w| format!("{w:.5}")).unwrap_or_else(|| "-".into())
        );
    }
    h += "</table>\n";
    if floor.is_some() {
        h +=
            "<p>The last row is the reference's own noise: what a perfect renderer would measure. \
A figure near it says more about the reference than about the run (see docs/math.md).</p>\n";
    }
    h += "<h2>Charts</h2>\n<div class=\"charts\">\n";
    for (t, svg) in charts {
        h += &format!(
            "<figure class=\"chart\" title=\"{}\">{}</figure>\n",
            esc(t),
            svg
        );
    }
    h += "</div>\n<h2>Animations</h2>\n<p>Top: the frames. Below: |lum(test) - lum(reference)|, scaled.</p>\n<div class=\"clips\">\n";
    for c in clips {
        h += &format!(
            "<div class=\"clip\"><div>{}</div><img alt=\"{}\" src=\"{}\">",
            esc(&c.label),
            esc(&c.label),
            gif_uri(&c.gif)
        );
        if let Some(e) = &c.error_gif {
            h += &format!(
                "<img alt=\"{} error\" src=\"{}\">",
                esc(&c.label),
                gif_uri(e)
            );
        }
        h += "</div>\n";
    }
    h += "</div>\n<p id=\"check\">checking images...</p>\n";
    h += "<script>window.addEventListener('load',()=>{const imgs=[...document.images];\
const bad=imgs.filter(i=>!(i.complete&&i.naturalWidth>0));\
const charts=document.querySelectorAll('figure.chart svg').length;\
document.getElementById('check').textContent=(bad.length==0?'report-ok':'report-broken')+\
' images='+imgs.length+' broken='+bad.length+' charts='+charts;});</script>\n";
    h += "</body></html>\n";
    h
}
