//! Prints relMSE, RMSE and bias of one EXR against another: `compare_images TEST REF`.
fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let t = irad::image::Hdr::read(std::path::Path::new(&a[1]))?;
    let r = irad::image::Hdr::read(std::path::Path::new(&a[2]))?;
    let e = irad::metrics::frame_error(&t, &r)?;
    println!(
        "relMSE {:.5}  RMSE {:.5}  bias {:+.5} ({:+.2}%)  mean test {:?} ref {:?}",
        e.rel_mse,
        e.rmse,
        e.bias,
        e.rel_bias * 100.0,
        t.mean(),
        r.mean()
    );
    Ok(())
}
