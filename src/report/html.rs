//! The self-contained report page: charts inline as SVG, animations and error images as
//! base64 GIFs, a sentence naming the steadiest run near the lowest error, a summary table, and
//! a check script that marks the page, invisibly, when every image has loaded (the browser test
//! reads it).

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

/// One run's flicker heat maps: every frame pair tiled on one sheet, and the frame pair with
/// the largest warped F1 on its own; PNG bytes (embedded) and their file names (linked).
pub struct HeatMap {
    pub label: String,
    pub sheet: Vec<u8>,
    pub sheet_file: String,
    /// The frame t of the pair (t-1, t) with the largest flicker, and its warped F1.
    pub worst_frame: u32,
    pub worst_f1: f64,
    pub worst: Vec<u8>,
    pub worst_file: String,
}

/// The heat maps of every shown run, on one colour scale.
pub struct Heat {
    /// The flicker value drawn with the ramp's top colour (and above it).
    pub top: f64,
    /// The colour bar (PNG), with the left-out grey at its right.
    pub legend: Vec<u8>,
    /// The frame numbers of the sheets' tiles, in reading order, and tiles to a row.
    pub frames: Vec<u32>,
    pub cols: u32,
    pub maps: Vec<HeatMap>,
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

fn png_uri(bytes: &[u8]) -> String {
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

/// The heat maps' section.
/// The sentence at the top of the page: of the runs whose relMSE is at most 1.1x the lowest,
/// the one with the least warped flicker F1 (equal to the plain F1 where nothing moves), and
/// the run with the lowest relMSE beside it. None without a run with finite figures.
pub fn verdict(rows: &[Row]) -> Option<String> {
    let ok: Vec<&Row> = rows
        .iter()
        .filter(|r| r.rel_mse.is_finite() && r.warped.is_finite())
        .collect();
    let best = ok.iter().min_by(|a, b| a.rel_mse.total_cmp(&b.rel_mse))?;
    let steady = ok
        .iter()
        .filter(|r| r.rel_mse <= best.rel_mse * 1.1)
        .min_by(|a, b| a.warped.total_cmp(&b.warped))?;
    let steadiest = ok.iter().min_by(|a, b| a.warped.total_cmp(&b.warped))?;
    let mut s = if std::ptr::eq(*steady, *best) {
        format!(
            "{} has the lowest relMSE ({:.5}), and no run within 1.1x of it flickers less \
(warped flicker F1 {:.5}).",
            best.label, best.rel_mse, best.warped
        )
    } else {
        format!(
            "Among the runs whose relMSE is within 1.1x of the lowest ({}: {:.5}, warped flicker F1 {:.5}), \
{} flickers least: warped flicker F1 {:.5} at relMSE {:.5}.",
            best.label, best.rel_mse, best.warped, steady.label, steady.warped, steady.rel_mse
        )
    };
    if !std::ptr::eq(*steadiest, *steady) {
        s += &format!(
            " The least flicker of all runs is {}'s ({:.5}), at relMSE {:.5}.",
            steadiest.label, steadiest.warped, steadiest.rel_mse
        );
    }
    Some(s)
}

fn heat_section(heat: &Heat) -> String {
    let mut h = String::from("<h2>Flicker heat maps</h2>\n");
    let (first, last) = (
        heat.frames.first().copied().unwrap_or(0),
        heat.frames.last().copied().unwrap_or(0),
    );
    h += &format!(
        "<p>Per pixel |e_t - warp(e_(t-1))|, e = lum(test) - lum(reference): the quantity whose mean is the \
warped F1 (the plain difference where nothing moves). One tile per frame t = {first}..{last} in reading order, \
{} to a row; the largest frame pair on the right. One scale for every run: \
<img class=\"legend\" alt=\"colour scale\" src=\"{}\"> black 0 to pale yellow {:.3e} (and above); \
grey: left out by the warp (hidden or off screen in the frame before).</p>\n<div class=\"heat\">\n",
        heat.cols,
        png_uri(&heat.legend),
        heat.top
    );
    for m in &heat.maps {
        h += &format!(
            "<div class=\"heatrow\"><div>{}</div><a href=\"{}\"><img class=\"sheet\" alt=\"{} flicker, every frame\" src=\"{}\"></a>\
<figure><a href=\"{}\"><img class=\"worst\" alt=\"{} flicker, frame {}\" src=\"{}\"></a>\
<figcaption>frame {} (warped F1 {:.5})</figcaption></figure></div>\n",
            esc(&m.label),
            esc(&m.sheet_file),
            esc(&m.label),
            png_uri(&m.sheet),
            esc(&m.worst_file),
            esc(&m.label),
            m.worst_frame,
            png_uri(&m.worst),
            m.worst_frame,
            m.worst_f1
        );
    }
    h += "</div>\n";
    h
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
    heat: Option<&Heat>,
) -> String {
    let mut h = String::new();
    h += "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
    h += &format!("<title>{}</title>\n", esc(title));
    h += "<style>body{font-family:sans-serif;margin:24px;color:#222;max-width:1600px}\
table{border-collapse:collapse;margin:12px 0}td,th{border:1px solid #bbb;padding:4px 10px;text-align:right}\
th{background:#eee}td:first-child{text-align:left}.charts{display:flex;flex-wrap:wrap;gap:12px}\
.charts figure{margin:0}.clips{display:flex;flex-wrap:wrap;gap:16px}.clip{text-align:center}\
.clip img{image-rendering:pixelated;width:256px;display:block;margin:2px}\
.heatrow{display:flex;gap:16px;align-items:flex-start;margin:8px 0}.heatrow>div{width:140px}\
.heat img{image-rendering:pixelated}.heat img.sheet{width:720px}.heat img.worst{width:256px}.legend{vertical-align:middle}\
.verdict{font-size:17px}#check{display:none}</style>\n";
    h += "</head><body>\n";
    h += &format!("<h1>{}</h1>\n", esc(title));
    if let Some(v) = verdict(rows) {
        h += &format!("<p class=\"verdict\">{}</p>\n", esc(&v));
    }
    h += "<ul>\n";
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
    // The SVG carries its own caption, written from its data (charts.rs).
    for (_, svg) in charts {
        h += &format!("<figure class=\"chart\">{svg}</figure>\n");
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
    h += "</div>\n";
    if let Some(heat) = heat {
        h += &heat_section(heat);
    }
    // The browser test reads this line (every image loaded, how many); it is not shown.
    h += "<p id=\"check\">checking images...</p>\n";
    h += "<script>window.addEventListener('load',()=>{const imgs=[...document.images];\
const bad=imgs.filter(i=>!(i.complete&&i.naturalWidth>0));\
const charts=document.querySelectorAll('figure.chart svg').length;\
document.getElementById('check').textContent=(bad.length==0?'report-ok':'report-broken')+\
' images='+imgs.length+' broken='+bad.length+' charts='+charts;});</script>\n";
    h += "</body></html>\n";
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(label: &str, rel_mse: f64, warped: f64) -> Row {
        Row {
            label: label.into(),
            seconds: 0.1,
            rel_mse,
            flip: 0.1,
            flicker: warped,
            warped,
            replaced: 1.0,
            acceptance: None,
        }
    }

    #[test]
    fn the_verdict_names_the_steadiest_run_near_the_lowest_error() {
        // cdf has the lowest error; smc is within 1.1x of it and flickers less; frozen
        // flickers least of all but at twice the error.
        let rows = [
            row("cdf 256", 0.0100, 0.0090),
            row("smc 256", 0.0105, 0.0030),
            row("frozen 256", 0.0200, 0.0010),
            row("broken", f64::NAN, 0.0),
        ];
        let v = verdict(&rows).unwrap();
        assert!(
            v.starts_with(
                "Among the runs whose relMSE is within 1.1x of the lowest (cdf 256: 0.01000"
            ),
            "{v}"
        );
        assert!(
            v.contains("smc 256 flickers least: warped flicker F1 0.00300 at relMSE 0.01050"),
            "{v}"
        );
        assert!(
            v.contains(
                "The least flicker of all runs is frozen 256's (0.00100), at relMSE 0.02000."
            ),
            "{v}"
        );
        let v = verdict(&rows[..1]).unwrap();
        assert!(
            v.starts_with("cdf 256 has the lowest relMSE (0.01000), and no run within 1.1x"),
            "{v}"
        );
        assert!(!v.contains("least flicker of all"), "{v}");
        assert!(verdict(&[]).is_none());
    }
}
