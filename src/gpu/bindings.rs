//! Each pass states its bindings once, in a [`Pass`] table: per bind group, the WGSL name,
//! kind and access of every binding, and for buffers the Rust struct (declared with
//! [`gpu_struct!`]) or element size the shader reads. The same table builds the bind-group
//! layout and the bind group, and the test below parses every WGSL file with naga and checks
//! the tables and the Rust structs' sizes and field offsets against the shaders.

use super::Gpu;

/// One field of a Rust struct shared with WGSL: name, byte offset and byte size.
#[derive(Debug)]
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) struct FieldLayout {
    pub name: &'static str,
    pub offset: usize,
    pub size: usize,
}

/// A Rust struct's memory layout, to compare with its WGSL twin (of the same name).
#[derive(Debug)]
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) struct StructLayout {
    pub wgsl: &'static str,
    pub size: usize,
    pub fields: &'static [FieldLayout],
}

/// Declares a `#[repr(C)]` plain-old-data struct shared with WGSL (a struct of the same name
/// in the pass's shader), with its layout as the associated constant `LAYOUT`.
macro_rules! gpu_struct {
    ($(#[$m:meta])* $vis:vis struct $name:ident {
        $($(#[$fm:meta])* $fvis:vis $field:ident : $ty:ty),* $(,)?
    }) => {
        $(#[$m])*
        #[repr(C)]
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name {
            $($(#[$fm])* $fvis $field: $ty),*
        }
        $crate::gpu::bindings::gpu_layout!($name { $($field: $ty),* });
    };
}
pub(crate) use gpu_struct;

/// The layout constant `LAYOUT` of a `#[repr(C)]` struct declared elsewhere (by a lower
/// stage, without the GPU's macros) that WGSL shares: `gpu_layout!(Point { tri: u32, .. })`.
macro_rules! gpu_layout {
    ($name:ident { $($field:ident : $ty:ty),* $(,)? }) => {
        impl $name {
            /// This struct's layout, checked against its WGSL twin in a test.
            #[allow(dead_code)]
            pub(crate) const LAYOUT: $crate::gpu::bindings::StructLayout =
                $crate::gpu::bindings::StructLayout {
                    wgsl: stringify!($name),
                    size: std::mem::size_of::<$name>(),
                    fields: &[$($crate::gpu::bindings::FieldLayout {
                        name: stringify!($field),
                        offset: std::mem::offset_of!($name, $field),
                        size: std::mem::size_of::<$ty>(),
                    }),*],
                };
        }
    };
}
pub(crate) use gpu_layout;

/// What a storage buffer holds: `array<Struct>` or an array of a plain type of this stride.
#[derive(Debug)]
pub(crate) enum Elem {
    Struct(&'static StructLayout),
    /// `u32`, `f32`, `atomic<u32>` (4) or `vec4f` (16).
    Plain(u64),
}

impl Elem {
    pub(crate) fn size(&self) -> u64 {
        match self {
            Elem::Struct(s) => s.size as u64,
            Elem::Plain(n) => *n,
        }
    }
}

/// The kind and access of one binding.
#[derive(Debug)]
pub(crate) enum Kind {
    /// `var<uniform> name: Struct`, optionally bound at a dynamic offset.
    Uniform {
        ty: &'static StructLayout,
        dynamic: bool,
    },
    /// `var<storage, read> name: Struct`: a compute pass's parameters. Compute passes read
    /// their parameters from a read-only storage buffer, not a uniform buffer: lavapipe
    /// (Mesa 22.3) inlines uniform-buffer values that a loop depends on and recompiles the
    /// shader at every dispatch, keeping each compiled copy (0.18 MiB a dispatch for the
    /// direct pass; `examples/lavapipe_growth.rs`). Storage buffers are not inlined.
    Params(&'static StructLayout),
    /// `var<storage, read|read_write> name: array<elem>`.
    Storage { elem: Elem, read_only: bool },
    /// `var name: texture_2d<u32>` (or `texture_2d_array<u32>`), read with `textureLoad`.
    TextureUint(wgpu::TextureViewDimension),
}

/// One binding: its WGSL variable name and kind; its index is its place in the group.
#[derive(Debug)]
pub(crate) struct Binding {
    pub name: &'static str,
    pub kind: Kind,
}

/// One bind group: the shader stages that see it and its bindings, in binding order.
#[derive(Debug)]
pub(crate) struct Group {
    pub stages: wgpu::ShaderStages,
    pub bindings: &'static [Binding],
}

/// A pass: its WGSL (without the common code) and its bind groups, in group order.
#[derive(Debug)]
pub(crate) struct Pass {
    pub name: &'static str,
    pub wgsl: &'static str,
    pub groups: &'static [Group],
}

/// A uniform at a fixed offset (no pass uses one now that the G-buffer's cameras sit at
/// dynamic offsets; the layout test still checks the kind).
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) const fn uniform(name: &'static str, ty: &'static StructLayout) -> Binding {
    Binding {
        name,
        kind: Kind::Uniform { ty, dynamic: false },
    }
}

/// A compute pass's parameters: `var<storage, read> name: Struct` (see [`Kind::Params`]).
pub(crate) const fn params(name: &'static str, ty: &'static StructLayout) -> Binding {
    Binding {
        name,
        kind: Kind::Params(ty),
    }
}

/// A uniform bound at a dynamic offset (one buffer of many values).
pub(crate) const fn dynamic_uniform(name: &'static str, ty: &'static StructLayout) -> Binding {
    Binding {
        name,
        kind: Kind::Uniform { ty, dynamic: true },
    }
}

pub(crate) const fn read(name: &'static str, elem: Elem) -> Binding {
    Binding {
        name,
        kind: Kind::Storage {
            elem,
            read_only: true,
        },
    }
}

pub(crate) const fn read_write(name: &'static str, elem: Elem) -> Binding {
    Binding {
        name,
        kind: Kind::Storage {
            elem,
            read_only: false,
        },
    }
}

pub(crate) const fn texture(name: &'static str, dim: wgpu::TextureViewDimension) -> Binding {
    Binding {
        name,
        kind: Kind::TextureUint(dim),
    }
}

impl Binding {
    pub(crate) fn layout_entry(
        &self,
        binding: u32,
        visibility: wgpu::ShaderStages,
    ) -> wgpu::BindGroupLayoutEntry {
        let buffer = |ty, dynamic, min: u64| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic,
            min_binding_size: wgpu::BufferSize::new(min),
        };
        let ty = match &self.kind {
            Kind::Uniform { ty, dynamic } => {
                buffer(wgpu::BufferBindingType::Uniform, *dynamic, ty.size as u64)
            }
            Kind::Params(ty) => buffer(
                wgpu::BufferBindingType::Storage { read_only: true },
                false,
                ty.size as u64,
            ),
            Kind::Storage { elem, read_only } => buffer(
                wgpu::BufferBindingType::Storage {
                    read_only: *read_only,
                },
                false,
                elem.size(),
            ),
            Kind::TextureUint(dim) => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Uint,
                view_dimension: *dim,
                multisampled: false,
            },
        };
        wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        }
    }
}

impl Group {
    pub(crate) fn layout(&self, gpu: &Gpu, label: &str) -> wgpu::BindGroupLayout {
        let entries: Vec<_> = self
            .bindings
            .iter()
            .enumerate()
            .map(|(i, b)| b.layout_entry(i as u32, self.stages))
            .collect();
        gpu.device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            })
    }

    /// A bind group of `layout` (built by [`Group::layout`]) from resources named as in the
    /// table (any order). A name missing from either side is a programming error.
    pub(crate) fn bind(
        &self,
        gpu: &Gpu,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        resources: &[(&str, wgpu::BindingResource)],
    ) -> wgpu::BindGroup {
        assert_eq!(
            resources.len(),
            self.bindings.len(),
            "{label}: {} resources for {} bindings",
            resources.len(),
            self.bindings.len()
        );
        let entries: Vec<wgpu::BindGroupEntry> = self
            .bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let (_, r) = resources
                    .iter()
                    .find(|(n, _)| *n == b.name)
                    .unwrap_or_else(|| panic!("{label}: no resource for binding `{}`", b.name));
                wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: r.clone(),
                }
            })
            .collect();
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries: &entries,
        })
    }
}

impl Pass {
    pub(crate) fn module(&self, gpu: &Gpu) -> wgpu::ShaderModule {
        gpu.shader(self.name, self.wgsl)
    }

    /// The layouts of every group, in group order.
    pub(crate) fn layouts(&self, gpu: &Gpu) -> Vec<wgpu::BindGroupLayout> {
        self.groups
            .iter()
            .map(|g| g.layout(gpu, self.name))
            .collect()
    }
}

/// Bytes of `n` elements of `T`.
pub(crate) fn bytes<T>(n: u64) -> u64 {
    n * std::mem::size_of::<T>() as u64
}

/// Every pass's table, for the layout test: the frame's passes as the renderer's graph
/// lists them, and the classical methods' two.
#[cfg(test)]
pub(crate) fn all_passes() -> Vec<&'static Pass> {
    let frame = super::renderer::graph::GRAPH.iter().flat_map(|p| p.tables);
    frame
        .copied()
        .chain([&super::hemicube::PASS, &super::radiosity::PASS])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use naga::{AddressSpace, ImageClass, ImageDimension, ScalarKind, StorageAccess, TypeInner};

    /// What differs between `pass`'s table and its WGSL (empty when they agree).
    fn check_pass(pass: &Pass) -> Vec<String> {
        let src = format!("{}\n{}", super::super::COMMON_WGSL, pass.wgsl);
        let module = match naga::front::wgsl::parse_str(&src) {
            Ok(m) => m,
            Err(e) => return vec![format!("{}: {}", pass.name, e.emit_to_string(&src))],
        };
        let mut layouter = naga::proc::Layouter::default();
        if let Err(e) = layouter.update(module.to_ctx()) {
            return vec![format!("{}: layout: {e}", pass.name)];
        }
        let mut errs = Vec::new();
        let mut seen = 0;
        for (_, var) in module.global_variables.iter() {
            let Some(rb) = &var.binding else { continue };
            seen += 1;
            let name = var.name.as_deref().unwrap_or("?");
            let at = format!(
                "{} @group({}) @binding({}) `{name}`",
                pass.name, rb.group, rb.binding
            );
            let Some(b) = pass
                .groups
                .get(rb.group as usize)
                .and_then(|g| g.bindings.get(rb.binding as usize))
            else {
                errs.push(format!("{at}: not in the Rust table"));
                continue;
            };
            if b.name != name {
                errs.push(format!("{at}: the Rust table names it `{}`", b.name));
            }
            let inner = &module.types[var.ty].inner;
            match (&b.kind, var.space, inner) {
                (Kind::Uniform { ty, .. }, AddressSpace::Uniform, _) => {
                    errs.extend(check_struct(&module, &layouter, var.ty, ty, &at));
                }
                (Kind::Params(ty), AddressSpace::Storage { access }, TypeInner::Struct { .. }) => {
                    if access.contains(StorageAccess::STORE) {
                        errs.push(format!("{at}: parameters are read_write in WGSL"));
                    }
                    errs.extend(check_struct(&module, &layouter, var.ty, ty, &at));
                }
                (
                    Kind::Storage { elem, read_only },
                    AddressSpace::Storage { access },
                    TypeInner::Array { base, stride, .. },
                ) => {
                    let ro = !access.contains(StorageAccess::STORE);
                    if ro != *read_only {
                        errs.push(format!("{at}: read-only {ro} in WGSL, {read_only} in Rust"));
                    }
                    if *stride as u64 != elem.size() {
                        errs.push(format!(
                            "{at}: element stride {stride} in WGSL, {} in Rust",
                            elem.size()
                        ));
                    }
                    if let Elem::Struct(s) = elem {
                        errs.extend(check_struct(&module, &layouter, *base, s, &at));
                    }
                }
                (
                    Kind::TextureUint(dim),
                    AddressSpace::Handle,
                    TypeInner::Image {
                        dim: d,
                        arrayed,
                        class,
                    },
                ) => {
                    let want = match (d, arrayed) {
                        (ImageDimension::D2, false) => wgpu::TextureViewDimension::D2,
                        (ImageDimension::D2, true) => wgpu::TextureViewDimension::D2Array,
                        _ => wgpu::TextureViewDimension::D3,
                    };
                    if want != *dim {
                        errs.push(format!("{at}: {want:?} in WGSL, {dim:?} in Rust"));
                    }
                    let uint = matches!(
                        class,
                        ImageClass::Sampled {
                            kind: ScalarKind::Uint,
                            multi: false
                        }
                    );
                    if !uint {
                        errs.push(format!("{at}: {class:?} in WGSL, a u32 texture in Rust"));
                    }
                }
                (k, space, _) => {
                    errs.push(format!("{at}: {space:?} {inner:?} in WGSL, {k:?} in Rust"))
                }
            }
        }
        let declared: usize = pass.groups.iter().map(|g| g.bindings.len()).sum();
        if declared != seen {
            errs.push(format!(
                "{}: {declared} bindings in the Rust table, {seen} in WGSL",
                pass.name
            ));
        }
        errs
    }

    /// What differs between the WGSL struct `ty` and the Rust struct `rust`.
    fn check_struct(
        module: &naga::Module,
        layouter: &naga::proc::Layouter,
        ty: naga::Handle<naga::Type>,
        rust: &StructLayout,
        at: &str,
    ) -> Vec<String> {
        let t = &module.types[ty];
        let TypeInner::Struct { members, span } = &t.inner else {
            return vec![format!(
                "{at}: {:?} in WGSL, struct {} in Rust",
                t.inner, rust.wgsl
            )];
        };
        let name = t.name.as_deref().unwrap_or("?");
        let at = format!("{at}: struct {name}");
        let mut errs = Vec::new();
        if name != rust.wgsl {
            errs.push(format!("{at}: named {} in Rust", rust.wgsl));
        }
        if *span as usize != rust.size {
            errs.push(format!("{at}: {span} bytes in WGSL, {} in Rust", rust.size));
        }
        if members.len() != rust.fields.len() {
            errs.push(format!(
                "{at}: {} fields in WGSL, {} in Rust",
                members.len(),
                rust.fields.len()
            ));
        }
        for (m, f) in members.iter().zip(rust.fields) {
            let wsize = layouter[m.ty].size as usize;
            let wname = m.name.as_deref().unwrap_or("?");
            if wname != f.name || m.offset as usize != f.offset || wsize != f.size {
                errs.push(format!(
                    "{at}: field `{wname}` at {} ({wsize} bytes) in WGSL, `{}` at {} ({} bytes) in Rust",
                    m.offset, f.name, f.offset, f.size
                ));
            }
        }
        errs
    }

    /// Every pass's binding table and Rust structs agree with its WGSL, as naga parses and
    /// lays it out.
    #[test]
    fn binding_tables_and_structs_match_the_shaders() {
        let errs: Vec<String> = all_passes().into_iter().flat_map(check_pass).collect();
        assert!(
            errs.is_empty(),
            "{} mismatches:\n{}",
            errs.len(),
            errs.join("\n")
        );
    }

    /// No compute pass reads a uniform buffer (see [`Kind::Params`]: on lavapipe that
    /// recompiles the shader at every dispatch and the process grows without bound).
    #[test]
    fn compute_passes_take_their_parameters_from_storage() {
        let uniforms: Vec<String> = all_passes()
            .into_iter()
            .flat_map(|p| p.groups.iter().map(move |g| (p.name, g)))
            // Compute-only groups (the radiosity pass's one group also holds its raster's
            // camera, which only the vertex and fragment stages bind).
            .filter(|(_, g)| g.stages == wgpu::ShaderStages::COMPUTE)
            .flat_map(|(name, g)| {
                g.bindings
                    .iter()
                    .filter(|b| matches!(b.kind, Kind::Uniform { .. }))
                    .map(move |b| format!("{name}: `{}`", b.name))
            })
            .collect();
        assert!(uniforms.is_empty(), "compute uniforms: {uniforms:?}");
    }

    /// The checker itself finds a drift: a table naming, typing or ordering a binding
    /// differently from the shader, and a struct whose field moved.
    #[test]
    fn the_check_catches_drift() {
        const WGSL: &str = "@group(0) @binding(0) var<uniform> P: FrameConstants;
@group(0) @binding(1) var<storage, read_write> out: array<vec4f>;
@compute @workgroup_size(1) fn main() { out[0] = vec4f(f32(P.width)); }";
        static SWAPPED: [Binding; 2] = [
            read_write("out", Elem::Plain(16)),
            uniform("P", &super::super::common::FrameConstants::LAYOUT),
        ];
        static READ_ONLY: [Binding; 2] = [
            uniform("P", &super::super::common::FrameConstants::LAYOUT),
            read("out", Elem::Plain(16)),
        ];
        static WRONG_STRUCT: [Binding; 2] = [
            uniform("P", &super::super::common::Tri::LAYOUT),
            read_write("out", Elem::Plain(16)),
        ];
        static RIGHT: [Binding; 2] = [
            uniform("P", &super::super::common::FrameConstants::LAYOUT),
            read_write("out", Elem::Plain(16)),
        ];
        let pass = |bindings: &'static [Binding]| -> &'static Pass {
            Box::leak(Box::new(Pass {
                name: "drift",
                wgsl: WGSL,
                groups: Box::leak(Box::new([Group {
                    stages: wgpu::ShaderStages::COMPUTE,
                    bindings,
                }])),
            }))
        };
        assert_eq!(check_pass(pass(&RIGHT)), Vec::<String>::new());
        for (what, b) in [
            ("swapped", &SWAPPED),
            ("read-only", &READ_ONLY),
            ("struct", &WRONG_STRUCT),
        ] {
            let errs = check_pass(pass(b));
            assert!(!errs.is_empty(), "{what}: drift not found");
        }
    }
}
