//! `irad._irad`: the native half of the Python package (python/irad/ is the other). Settings
//! arrive as the command line's flags (`["--vpls", "64", ...]`, written by `irad/__init__.py`
//! from keyword arguments) and are parsed by irad's own clap types, so every keyword has the
//! flag's name, default and checks; rendering goes through the library calls the CLI makes
//! (`commands::render::start`, `Pipeline::render_frame`, `commands::reference::trace_frames`,
//! `metrics::*`). Errors become Python exceptions (see [`py_err`]); no panic reaches Python
//! (pyo3 turns one into `PanicException`; [`guard`] turns it into a `RuntimeError` first).

use anyhow::{anyhow, Context};
use irad::config;
use irad::frame::Pipeline;
use irad::gpu::{BackendChoice, Gpu};
use irad::image::Hdr;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyFileNotFoundError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

create_exception!(
    _irad,
    SettingsError,
    PyValueError,
    "A setting irad refuses; `argument` names the keyword argument (the CLI's flag)."
);

/// The process's one GPU device (and the backend it was opened for), shared by every render.
static GPU: Mutex<Option<(BackendChoice, Arc<Gpu>)>> = Mutex::new(None);

fn device(backend: BackendChoice) -> anyhow::Result<Arc<Gpu>> {
    let mut held = GPU.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((b, gpu)) = &*held {
        if *b == backend {
            return Ok(gpu.clone());
        }
    }
    irad::gpu::quiet_mesa_runtime_dir();
    let gpu = Arc::new(Gpu::new(backend)?);
    *held = Some((backend, gpu.clone()));
    Ok(gpu)
}

/// The settings' names (every long flag of every subcommand, `-` as `_`): the keyword
/// arguments.
fn setting_names() -> std::collections::HashSet<String> {
    use clap::CommandFactory;
    let cmd = irad::cli::Cli::command();
    let mut names = std::collections::HashSet::new();
    for sub in std::iter::once(&cmd).chain(cmd.get_subcommands()) {
        for a in sub.get_arguments() {
            if let Some(l) = a.get_long() {
                names.insert(l.replace('-', "_"));
            }
        }
    }
    // The arguments of the metrics functions that no flag has.
    for n in ["scene", "test", "reference", "halves", "image"] {
        names.insert(n.into());
    }
    names
}

/// `text` with each known setting in backquotes or written as a flag given as its keyword;
/// and the first one named.
fn keywords(text: &str) -> (String, Option<String>) {
    let names = setting_names();
    let mut first = None;
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(a) = rest.find(['`', '-']) {
        out.push_str(&rest[..a]);
        let tail = &rest[a..];
        let (name, len) = if let Some(t) = tail.strip_prefix('`') {
            match t.find('`') {
                Some(b) => (t[..b].to_string(), b + 2),
                None => (String::new(), 0),
            }
        } else if let Some(t) = tail.strip_prefix("--") {
            let b = t
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                .unwrap_or(t.len());
            (t[..b].replace('-', "_"), b + 2)
        } else {
            (String::new(), 0)
        };
        if len > 0 && names.contains(&name) {
            out.push_str(&name);
            first.get_or_insert(name);
            rest = &tail[len..];
        } else {
            out.push_str(&tail[..1]);
            rest = &tail[1..];
        }
    }
    out.push_str(rest);
    (out, first)
}

/// An irad error as a Python exception: a missing file `FileNotFoundError`, a refused setting
/// `SettingsError` (a `ValueError`) with `argument` set, anything else `RuntimeError`.
fn py_err(e: anyhow::Error) -> PyErr {
    let not_found = e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::NotFound)
    }) || format!("{e}").contains("no such file, and not a built-in scene");
    let (text, name) = keywords(&format!("{e:#}"));
    if not_found {
        return PyFileNotFoundError::new_err(text);
    }
    match name {
        Some(name) => settings_error(text, &name),
        None => PyRuntimeError::new_err(text),
    }
}

fn settings_error(text: String, name: &str) -> PyErr {
    Python::attach(|py| {
        let e = SettingsError::new_err(text);
        let _ = e.value(py).setattr("argument", name);
        e
    })
}

/// Runs `f` without the GIL; a panic in it comes back as a `RuntimeError` (a bug in irad, not
/// something bad input should reach).
fn guard<T: Send>(py: Python<'_>, f: impl FnOnce() -> anyhow::Result<T> + Send) -> PyResult<T> {
    py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|p| {
            let what = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(anyhow!("internal error in irad (please report): {what}"))
        })
    })
    .map_err(py_err)
}

/// Parses `irad SUBCOMMAND ARGS...` with the CLI's own types.
fn parse(sub: &str, args: Vec<String>) -> PyResult<irad::cli::Command> {
    use clap::Parser;
    let argv = ["irad".to_string(), sub.to_string()]
        .into_iter()
        .chain(args);
    let cmd = irad::cli::Cli::try_parse_from(argv)
        .map_err(|e| {
            use clap::error::{ContextKind, ContextValue, ErrorKind};
            let arg = match e.get(ContextKind::InvalidArg) {
                Some(ContextValue::String(s)) => s.clone(),
                _ => String::new(),
            };
            let flag = arg.split([' ', '=']).next().unwrap_or("");
            let name = flag.trim_start_matches('-').replace('-', "_");
            let text = e.render().to_string();
            // The first line, and clap's list of the values it takes.
            let mut line = text
                .lines()
                .next()
                .unwrap_or("")
                .trim_start_matches("error: ")
                .replace(&format!("'{arg}'"), &format!("'{name}'"));
            if let Some(values) = text.lines().find(|l| l.contains("[possible values:")) {
                line = format!("{line} {}", values.trim());
            }
            let (line, _) = keywords(&line);
            if e.kind() == ErrorKind::UnknownArgument {
                PyTypeError::new_err(format!("unexpected keyword argument '{name}'"))
            } else {
                settings_error(line, &name)
            }
        })?
        .command;
    cmd.validate().map_err(py_err)?;
    Ok(cmd)
}

fn to_array(py: Python<'_>, img: Hdr) -> Bound<'_, PyArray3<f32>> {
    let (w, h) = (img.width as usize, img.height as usize);
    let flat: Vec<f32> = img.data.iter().flat_map(|c| c.to_array()).collect();
    Array3::from_shape_vec((h, w, 3), flat)
        .expect("w*h*3 floats")
        .into_pyarray(py)
}

fn to_hdr(a: &PyReadonlyArray3<'_, f32>, what: &str) -> PyResult<Hdr> {
    let shape = a.shape();
    if shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
        return Err(settings_error(
            format!("{what}: an image is H x W x 3 (linear RGB), not {shape:?}"),
            what,
        ));
    }
    let data = a.as_array();
    let mut img = Hdr::new(shape[1] as u32, shape[0] as u32);
    for (i, p) in img.data.iter_mut().enumerate() {
        let (y, x) = (i / shape[1], i % shape[1]);
        *p = glam::Vec3::new(data[[y, x, 0]], data[[y, x, 1]], data[[y, x, 2]]);
    }
    Ok(img)
}

fn to_hdrs(list: Vec<PyReadonlyArray3<'_, f32>>, what: &str) -> PyResult<Vec<Hdr>> {
    list.iter().map(|a| to_hdr(a, what)).collect()
}

/// A scene: a built-in's name or a glTF file, loaded.
#[pyclass(module = "irad._irad", frozen)]
struct Scene {
    #[pyo3(get)]
    spec: String,
    scene: irad::scene::Scene,
}

fn load_scene(spec: &str, allow_outside_paths: bool) -> anyhow::Result<irad::scene::Scene> {
    irad::config::load_scene_with(
        spec,
        &irad::scene::load::LoadOptions {
            allow_outside_paths,
        },
    )
}

#[pymethods]
impl Scene {
    /// Loads a built-in scene by name (see `irad.builtins()`) or a .gltf/.glb file.
    #[staticmethod]
    #[pyo3(signature = (spec, allow_outside_paths = false))]
    fn load(py: Python<'_>, spec: PathBuf, allow_outside_paths: bool) -> PyResult<Scene> {
        let spec = spec.to_string_lossy().into_owned();
        let s = spec.clone();
        let scene = guard(py, move || load_scene(&s, allow_outside_paths))?;
        Ok(Scene { spec, scene })
    }

    /// Length of the animation in seconds (0 for a still scene).
    #[getter]
    fn duration(&self) -> f32 {
        self.scene.duration()
    }

    /// The loader's warnings.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    /// What `irad scenes FILE` prints, as data (its text under "text").
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        use pyo3::types::PyDict;
        let i = irad::scene::inspect::inspect(&self.scene);
        let v3 = |v: glam::Vec3| v.to_array().to_vec();
        let d = PyDict::new(py);
        d.set_item("name", &i.name)?;
        d.set_item("triangles", i.triangles)?;
        d.set_item("instances", i.instances.0)?;
        d.set_item("closed_instances", i.instances.1)?;
        d.set_item("closed_triangles", i.instances.2)?;
        let list = |items: Vec<Bound<'py, PyDict>>| items;
        let mut emitters = Vec::new();
        for e in &i.emitters {
            let x = PyDict::new(py);
            x.set_item("material", &e.material)?;
            x.set_item("triangles", e.triangles)?;
            x.set_item("power", v3(e.power))?;
            emitters.push(x);
        }
        d.set_item("emitters", list(emitters))?;
        let mut lights = Vec::new();
        for l in &i.lights {
            let x = PyDict::new(py);
            x.set_item("name", &l.name)?;
            x.set_item("kind", format!("{:?}", l.kind))?;
            x.set_item("position", v3(l.position))?;
            x.set_item("direction", v3(l.direction))?;
            x.set_item("intensity", v3(l.intensity))?;
            x.set_item("power", v3(l.power))?;
            lights.push(x);
        }
        d.set_item("lights", list(lights))?;
        match &i.environment {
            Some((name, power, default)) => {
                let x = PyDict::new(py);
                x.set_item("name", name)?;
                x.set_item("power", v3(*power))?;
                x.set_item("default", *default)?;
                d.set_item("environment", x)?;
            }
            None => d.set_item("environment", py.None())?,
        }
        let mut cameras = Vec::new();
        for c in &i.cameras {
            let x = PyDict::new(py);
            x.set_item("node", c.node)?;
            x.set_item("name", &c.name)?;
            x.set_item("yfov_deg", c.yfov_deg)?;
            x.set_item("in_use", c.in_use)?;
            cameras.push(x);
        }
        d.set_item("cameras", list(cameras))?;
        let c = PyDict::new(py);
        c.set_item("position", v3(i.camera.position))?;
        c.set_item("forward", v3(i.camera.forward))?;
        c.set_item("up", v3(i.camera.up))?;
        c.set_item("yfov_deg", i.camera.yfov.to_degrees())?;
        d.set_item("camera", c)?;
        d.set_item("channels", i.channels)?;
        d.set_item("duration", i.duration)?;
        let mut animated = Vec::new();
        for a in &i.animated {
            let x = PyDict::new(py);
            x.set_item("node", a.node)?;
            x.set_item("name", &a.name)?;
            x.set_item("properties", a.properties.clone())?;
            x.set_item("moves_camera", a.moves_camera)?;
            x.set_item("moves_light", a.moves_light)?;
            x.set_item("moves_emitter", a.moves_emitter)?;
            animated.push(x);
        }
        d.set_item("animated", list(animated))?;
        d.set_item("bounds", (v3(i.bounds.0), v3(i.bounds.1)))?;
        d.set_item("warnings", i.warnings.clone())?;
        d.set_item("text", i.to_string())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("Scene.load({:?})", self.spec)
    }
}

/// A scene argument: a `Scene`, or a name or path to load.
fn scene_of(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    outside: bool,
) -> PyResult<irad::scene::Scene> {
    if let Ok(s) = scene.cast::<Scene>() {
        return Ok(s.get().scene.clone());
    }
    let spec: PathBuf = scene
        .extract()
        .map_err(|_| PyTypeError::new_err("scene: a Scene, a built-in's name or a path"))?;
    Scene::load(py, spec, outside).map(|s| s.scene)
}

/// A render in progress: `irad render`'s pipeline, yielding each frame instead of writing it.
#[pyclass(module = "irad._irad")]
struct Renderer {
    /// (A pyclass is shared between threads: the pipeline, which is not `Sync`, is behind a
    /// lock.)
    pipeline: Mutex<Option<Pipeline>>,
    frames: std::ops::Range<u32>,
    components: bool,
    #[pyo3(get)]
    note: Option<String>,
    #[pyo3(get)]
    settings: String,
}

#[pymethods]
impl Renderer {
    /// `scene` (a Scene, or None for the flags' `scene`), `args` `irad render`'s flags.
    #[new]
    fn new(py: Python<'_>, scene: Option<&Bound<'_, PyAny>>, args: Vec<String>) -> PyResult<Self> {
        let irad::cli::Command::Render(cfg) = parse("render", args)? else {
            unreachable!("parsed as render")
        };
        let scene = match scene {
            Some(s) => Some(scene_of(py, s, cfg.sequence.allow_outside_paths)?),
            None => None,
        };
        let settings = serde_json::to_string(&cfg).map_err(|e| py_err(e.into()))?;
        let (pipeline, frames, note) = guard(py, || {
            let gpu = device(cfg.backend)?;
            irad::commands::render::start(gpu, &cfg, scene)
        })?;
        Ok(Renderer {
            pipeline: Mutex::new(Some(pipeline)),
            frames: frames.iter(),
            components: cfg.components,
            note,
            settings,
        })
    }

    /// The frames still to render, as (start, end).
    #[getter]
    fn remaining(&self) -> (u32, u32) {
        (self.frames.start, self.frames.end)
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    /// The next frame: (index, time, image, record as JSON, direct, indirect).
    #[allow(clippy::type_complexity)]
    fn __next__<'py>(
        &mut self,
        py: Python<'py>,
    ) -> PyResult<
        Option<(
            u32,
            f32,
            Bound<'py, PyArray3<f32>>,
            String,
            Option<Bound<'py, PyArray3<f32>>>,
            Option<Bound<'py, PyArray3<f32>>>,
        )>,
    > {
        let mut held = self.pipeline.lock().unwrap_or_else(|p| p.into_inner());
        let Some(f) = self.frames.next() else {
            // The device's pipeline goes as soon as the last frame is out.
            *held = None;
            return Ok(None);
        };
        let Some(pipeline) = held.as_mut() else {
            return Ok(None);
        };
        let components = self.components;
        let (fo, record) = guard(py, || {
            let fo = pipeline.render_frame(f, components)?;
            let record = irad::commands::render::FrameRecord::of(&fo);
            Ok((fo, serde_json::to_string(&record)?))
        })?;
        let image = fo.image;
        Ok(Some((
            fo.index,
            fo.time,
            to_array(py, image.hdr),
            record,
            image.direct.map(|d| to_array(py, d)),
            image.indirect.map(|i| to_array(py, i)),
        )))
    }
}

/// A frame's index, time and image.
type IndexedImage<'py> = (u32, f32, Bound<'py, PyArray3<f32>>);

/// `irad reference`'s frames, in memory: [(index, time, image)].
#[pyfunction]
#[pyo3(signature = (scene, args))]
fn reference<'py>(
    py: Python<'py>,
    scene: Option<&Bound<'py, PyAny>>,
    args: Vec<String>,
) -> PyResult<Vec<IndexedImage<'py>>> {
    let irad::cli::Command::Reference(cfg) = parse("reference", args)? else {
        unreachable!("parsed as reference")
    };
    let seq = &cfg.sequence;
    let scene = match scene {
        Some(s) => seq
            .prepare_scene(scene_of(py, s, seq.allow_outside_paths)?)
            .map_err(py_err)?,
        None => guard(py, || seq.load_scene(config::DEFAULT_STILL_SCENE))?,
    };
    let frames = seq.frames_or_first();
    // Ctrl-C between frames: Python's signal handlers run (briefly taking the GIL after each
    // frame) and a KeyboardInterrupt ends the trace.
    let mut interrupt: Option<PyErr> = None;
    let images = guard(py, || {
        let mut images = Vec::new();
        irad::commands::reference::trace_frames(
            &scene,
            seq,
            cfg.sampling(),
            frames.iter(),
            &|| {},
            &mut |f, t, img| {
                images.push((f, t, img));
                if let Err(e) = Python::attach(|py| py.check_signals()) {
                    interrupt = Some(e);
                    anyhow::bail!("interrupted");
                }
                Ok(())
            },
        )?;
        Ok(images)
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    let images = images?;
    Ok(images
        .into_iter()
        .map(|(f, t, img)| (f, t, to_array(py, img)))
        .collect())
}

/// Reads an EXR (linear) or PNG (sRGB decoded to linear) as H x W x 3 float32.
#[pyfunction]
fn read_image(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyArray3<f32>>> {
    let img = guard(py, || Hdr::read(&path))?;
    Ok(to_array(py, img))
}

/// Writes H x W x 3 linear float32 as OpenEXR (as `irad render` writes its frames).
#[pyfunction]
fn write_exr(py: Python<'_>, path: PathBuf, image: PyReadonlyArray3<'_, f32>) -> PyResult<()> {
    let img = to_hdr(&image, "image")?;
    guard(py, || img.write_exr(&path))
}

/// A folder's frames (frame_FFFF.exr, or .png): (numbers, paths).
#[pyfunction]
fn list_frames(py: Python<'_>, folder: PathBuf) -> PyResult<(Vec<u32>, Vec<PathBuf>)> {
    let found = guard(py, || irad::metrics::list_frames(&folder))?;
    Ok(found.into_iter().unzip())
}

/// `irad metrics TEST REFERENCE` on two folders: (frame numbers, metrics as JSON).
#[pyfunction]
fn metrics_folders(
    py: Python<'_>,
    test: PathBuf,
    reference: PathBuf,
) -> PyResult<(Vec<u32>, String)> {
    guard(py, || {
        let (numbers, t, r) = irad::metrics::read_pair(&test, &reference)?;
        let m = irad::metrics::sequence(&numbers, &t, &r)?;
        Ok((numbers, serde_json::to_string(&m)?))
    })
}

/// Error and flicker of test frames against reference frames (as JSON).
#[pyfunction]
fn metrics_sequence(
    py: Python<'_>,
    numbers: Vec<u32>,
    test: Vec<PyReadonlyArray3<'_, f32>>,
    reference: Vec<PyReadonlyArray3<'_, f32>>,
) -> PyResult<String> {
    let (t, r) = (to_hdrs(test, "test")?, to_hdrs(reference, "reference")?);
    guard(py, || {
        same_sizes(&t, &r)?;
        Ok(serde_json::to_string(&irad::metrics::sequence(
            &numbers, &t, &r,
        )?)?)
    })
}

fn same_sizes(t: &[Hdr], r: &[Hdr]) -> anyhow::Result<()> {
    for (i, (a, b)) in t.iter().zip(r).enumerate() {
        if (a.width, a.height) != (b.width, b.height) {
            anyhow::bail!(
                "image sizes differ: `test` frame {i} is {}x{} but `reference` frame {i} is {}x{}",
                a.width,
                a.height,
                b.width,
                b.height
            );
        }
    }
    Ok(())
}

/// The scene at frames `numbers` (frame f at f / fps), seen from `camera` if given.
fn scene_frames(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    camera: Option<String>,
    outside: bool,
) -> PyResult<irad::scene::Scene> {
    let mut s = scene_of(py, scene, outside)?;
    if let Some(c) = camera {
        let spec: config::CameraSpec = c
            .parse()
            .map_err(|e: String| settings_error(format!("camera {e}"), "camera"))?;
        spec.validate().map_err(py_err)?;
        spec.apply(&mut s).map_err(py_err)?;
    }
    Ok(s)
}

/// Warped flicker of test frames against reference frames of `scene` (as JSON).
#[pyfunction]
#[pyo3(signature = (numbers, test, reference, scene, fps, camera = None, allow_outside_paths = false))]
#[allow(clippy::too_many_arguments)]
fn metrics_warped(
    py: Python<'_>,
    numbers: Vec<u32>,
    test: Vec<PyReadonlyArray3<'_, f32>>,
    reference: Vec<PyReadonlyArray3<'_, f32>>,
    scene: &Bound<'_, PyAny>,
    fps: f32,
    camera: Option<String>,
    allow_outside_paths: bool,
) -> PyResult<String> {
    let (t, r) = (to_hdrs(test, "test")?, to_hdrs(reference, "reference")?);
    let s = scene_frames(py, scene, camera, allow_outside_paths)?;
    guard(py, || {
        same_sizes(&t, &r)?;
        let w = irad::metrics::warp::for_scene(&s, fps, &numbers, &t, &r)?;
        Ok(serde_json::to_string(&w)?)
    })
}

/// The reference's noise floor from its two halves (as JSON).
#[pyfunction]
#[pyo3(signature = (numbers, reference, half_a, half_b, spp, scene = None, fps = 24.0, camera = None, allow_outside_paths = false))]
#[allow(clippy::too_many_arguments)]
fn metrics_floor(
    py: Python<'_>,
    numbers: Vec<u32>,
    reference: Vec<PyReadonlyArray3<'_, f32>>,
    half_a: Vec<PyReadonlyArray3<'_, f32>>,
    half_b: Vec<PyReadonlyArray3<'_, f32>>,
    spp: (u32, u32),
    scene: Option<&Bound<'_, PyAny>>,
    fps: f32,
    camera: Option<String>,
    allow_outside_paths: bool,
) -> PyResult<String> {
    let r = to_hdrs(reference, "reference")?;
    let a = to_hdrs(half_a, "halves")?;
    let b = to_hdrs(half_b, "halves")?;
    let s = match scene {
        Some(s) => Some(scene_frames(py, s, camera, allow_outside_paths)?),
        None => None,
    };
    guard(py, || {
        irad::check::float("`fps`", fps, 0.0, true, 1000.0)?;
        let motion = match (&s, r.first()) {
            (Some(s), Some(first)) => {
                let frames: Vec<_> = numbers.iter().map(|&f| s.at(f as f32 / fps)).collect();
                Some(irad::metrics::warp::motion(
                    &frames,
                    first.width,
                    first.height,
                ))
            }
            _ => None,
        };
        let f =
            irad::metrics::floor::floor(&numbers, &r, [&a, &b], [spp.0, spp.1], motion.as_deref())?;
        Ok(serde_json::to_string(&f)?)
    })
}

/// relMSE, RMSE, bias and relative bias of one image against another (as JSON).
#[pyfunction]
fn frame_error(
    py: Python<'_>,
    test: PyReadonlyArray3<'_, f32>,
    reference: PyReadonlyArray3<'_, f32>,
) -> PyResult<String> {
    let (t, r) = (to_hdr(&test, "test")?, to_hdr(&reference, "reference")?);
    guard(py, || {
        same_sizes(std::slice::from_ref(&t), std::slice::from_ref(&r))?;
        Ok(serde_json::to_string(&irad::metrics::frame_error(&t, &r)?)?)
    })
}

/// FLIP of one image against another (as `irad metrics` measures it).
#[pyfunction]
fn flip(
    py: Python<'_>,
    test: PyReadonlyArray3<'_, f32>,
    reference: PyReadonlyArray3<'_, f32>,
) -> PyResult<f64> {
    let (t, r) = (to_hdr(&test, "test")?, to_hdr(&reference, "reference")?);
    guard(py, || {
        same_sizes(std::slice::from_ref(&t), std::slice::from_ref(&r))?;
        irad::metrics::flip(&t, &r)
    })
}

/// `irad compare` with `args`: writes its outputs into `out` and returns that folder.
#[pyfunction]
fn compare(py: Python<'_>, args: Vec<String>) -> PyResult<PathBuf> {
    let irad::cli::Command::Compare(cfg) = parse("compare", args)? else {
        unreachable!("parsed as compare")
    };
    guard(py, || {
        let gpu = device(cfg.render.backend)?;
        irad::commands::compare::compare_on(gpu, &cfg).context("irad compare")?;
        Ok(cfg.out.clone())
    })
}

/// The built-in scenes: (name, what it stresses).
#[pyfunction]
fn builtins() -> Vec<(&'static str, &'static str)> {
    irad::scene::builtin::BUILTINS
        .iter()
        .map(|b| (b.name, b.stresses))
        .collect()
}

/// The adapter the process renders on (opening the device if no render has yet).
#[pyfunction]
#[pyo3(signature = (backend = "auto"))]
fn adapter(py: Python<'_>, backend: &str) -> PyResult<String> {
    let irad::cli::Command::Render(cfg) =
        parse("render", vec!["--backend".into(), backend.into()])?
    else {
        unreachable!("parsed as render")
    };
    guard(py, || Ok(device(cfg.backend)?.adapter.to_string()))
}

#[pymodule]
fn _irad(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_class::<Renderer>()?;
    m.add("SettingsError", m.py().get_type::<SettingsError>())?;
    m.add_function(wrap_pyfunction!(reference, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(list_frames, m)?)?;
    m.add_function(wrap_pyfunction!(metrics_folders, m)?)?;
    m.add_function(wrap_pyfunction!(metrics_sequence, m)?)?;
    m.add_function(wrap_pyfunction!(metrics_warped, m)?)?;
    m.add_function(wrap_pyfunction!(metrics_floor, m)?)?;
    m.add_function(wrap_pyfunction!(frame_error, m)?)?;
    m.add_function(wrap_pyfunction!(flip, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(builtins, m)?)?;
    m.add_function(wrap_pyfunction!(adapter, m)?)?;
    Ok(())
}
