//! The shaders against their Rust twins, without a GPU, through naga's reflection:
//! - every pass's shader (with the shared prelude) parses and validates;
//! - every pass's declared bindings match its shader's, binding for binding, in kind and access
//!   mode, and a binding declared read-write is written by some entry point;
//! - `struct Frame` has exactly `FrameUniform`'s fields at the same offsets, and the generated
//!   constants reach the shaders with Rust's values;
//! - no shader indexes an array value with a variable (a copy of the whole value per access).

use fovea::render::frame::PASSES;
use fovea::render::gpu::{compose, COMMON};
use fovea::render::graph::{Access, PassDecl};
use fovea::render::uniforms::{constants, FrameUniform, FIELDS};
use naga::valid::{Capabilities, GlobalUse, ModuleInfo, ValidationFlags, Validator};

fn parse(name: &str, source: &str) -> (naga::Module, ModuleInfo) {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name} does not parse:\n{}", e.emit_to_string(source)));
    let info = Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name} does not validate: {e:?}"));
    (module, info)
}

fn pass_module(decl: &PassDecl) -> (naga::Module, ModuleInfo) {
    parse(decl.label, &compose(decl.shader))
}

/// What the shader says about one binding: its kind as an [`Access`] (dynamic offsets are the
/// layout's business, so both uniform forms read as `Uniform`) and how its entry points use it.
fn shader_bindings(
    decl: &PassDecl,
    module: &naga::Module,
    info: &ModuleInfo,
) -> Vec<(u32, String, Access, GlobalUse)> {
    let mut out = Vec::new();
    for (handle, var) in module.global_variables.iter() {
        let Some(binding) = &var.binding else {
            continue;
        };
        assert_eq!(binding.group, 0, "{}: only group 0 is used", decl.label);
        let access = match (var.space, &module.types[var.ty].inner) {
            (naga::AddressSpace::Uniform, _) => Access::Uniform,
            (naga::AddressSpace::Storage { access }, _) => {
                if access.contains(naga::StorageAccess::STORE) {
                    Access::ReadWrite
                } else {
                    Access::Read
                }
            }
            (naga::AddressSpace::Handle, naga::TypeInner::Image { arrayed: true, .. }) => {
                Access::TextureArray
            }
            (
                naga::AddressSpace::Handle,
                naga::TypeInner::Image {
                    class:
                        naga::ImageClass::Storage {
                            format: naga::StorageFormat::R32Uint,
                            ..
                        },
                    ..
                },
            ) => Access::WriteUint,
            (
                naga::AddressSpace::Handle,
                naga::TypeInner::Image {
                    class:
                        naga::ImageClass::Sampled {
                            kind: naga::ScalarKind::Uint,
                            ..
                        },
                    ..
                },
            ) => Access::UintTexture,
            (naga::AddressSpace::Handle, naga::TypeInner::Image { .. }) => Access::Texture,
            (naga::AddressSpace::Handle, naga::TypeInner::Sampler { .. }) => Access::Sampler,
            (space, ty) => panic!("{}: unexpected binding {space:?} {ty:?}", decl.label),
        };
        let mut used = GlobalUse::empty();
        for (i, ep) in module.entry_points.iter().enumerate() {
            if decl.entry_points.contains(&ep.name.as_str()) {
                used |= info.get_entry_point(i)[handle];
            }
        }
        let name = var.name.clone().unwrap_or_default();
        out.push((binding.binding, name, access, used));
    }
    out
}

#[test]
fn every_pass_shader_parses_and_validates() {
    parse("common.wgsl", &compose(""));
    for decl in PASSES {
        pass_module(decl);
    }
    assert!(COMMON.contains("struct Frame"));
}

#[test]
fn every_pass_runs_entry_points_its_shader_has() {
    for decl in PASSES {
        let (module, _) = pass_module(decl);
        for entry in decl.entry_points {
            assert!(
                module.entry_points.iter().any(|e| e.name == *entry),
                "{}: no entry point {entry}",
                decl.label
            );
        }
    }
}

#[test]
fn declared_bindings_match_the_shaders() {
    for decl in PASSES {
        let (module, info) = pass_module(decl);
        let found = shader_bindings(decl, &module, &info);
        for (slot, b) in decl.numbered() {
            let Some((_, var, access, used)) = found.iter().find(|f| f.0 == slot) else {
                panic!(
                    "{}: binding {slot} ({}) is not in the shader",
                    decl.label, b.name
                );
            };
            // Filtering is the layout's business too: both array forms read the same in WGSL.
            let declared = match b.access {
                Access::DynamicUniform { .. } => Access::Uniform,
                Access::Layers => Access::TextureArray,
                a => a,
            };
            assert_eq!(
                declared, *access,
                "{}: binding {slot} is declared {:?} {} but the shader's `{var}` is {access:?}",
                decl.label, b.access, b.name
            );
            assert!(
                !used.is_empty(),
                "{}: binding {slot} ({}) is declared but no entry point uses `{var}`",
                decl.label,
                b.name
            );
            if b.access.writes() {
                assert!(
                    used.intersects(GlobalUse::WRITE | GlobalUse::ATOMIC),
                    "{}: {} is declared read-write but `{var}` is never written: declare it read",
                    decl.label,
                    b.name
                );
            }
        }
        // And nothing the entry points use is left undeclared.
        for (slot, var, _, used) in &found {
            let declared = decl.numbered().any(|(s, _)| s == *slot);
            assert!(
                declared || used.is_empty(),
                "{}: the shader uses `{var}` at binding {slot}, which the pass does not declare",
                decl.label
            );
        }
    }
}

#[test]
fn frame_uniform_fields_and_offsets_match_the_wgsl_struct() {
    let (module, _) = parse("common.wgsl", &compose(""));
    let (_, frame) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("Frame"))
        .expect("struct Frame in common.wgsl");
    let naga::TypeInner::Struct { members, span } = &frame.inner else {
        panic!("Frame is not a struct");
    };
    let wgsl: Vec<(String, usize)> = members
        .iter()
        .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
        .collect();
    let rust: Vec<(String, usize)> = FIELDS
        .iter()
        .filter(|(name, _)| !name.starts_with('_'))
        .map(|(n, o)| (n.to_string(), *o))
        .collect();
    assert_eq!(wgsl, rust, "FrameUniform and struct Frame disagree");
    assert_eq!(*span as usize, std::mem::size_of::<FrameUniform>());
}

#[test]
fn shared_constants_reach_the_shaders_with_rusts_values() {
    let (module, _) = parse("common.wgsl", &compose(""));
    for (name, value) in constants() {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("{name} is not in the shader prelude"));
        let expr = &module.global_expressions[c.init];
        assert_eq!(
            *expr,
            naga::Expression::Literal(naga::Literal::U32(value)),
            "{name}"
        );
    }
}

#[test]
fn no_shader_carries_a_hand_copy_of_a_generated_constant() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        for (name, _) in constants() {
            assert!(
                !text.contains(&format!("const {name}:")),
                "{} defines {name}; it comes from src/render/uniforms.rs",
                path.display()
            );
        }
    }
}

#[test]
fn every_file_in_shaders_dir_belongs_to_a_pass() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            name == "common.wgsl" || PASSES.iter().any(|d| d.shader == text),
            "{name} is no pass's shader: give it a pass in render/pass/ and list it in frame.rs"
        );
    }
}

/// Where a function indexes an array *value* (a struct argument's array member, a `let` array)
/// with a variable: the function and the expression's index.
fn variable_indexes_into_values(module: &naga::Module, info: &ModuleInfo) -> Vec<String> {
    let mut found = Vec::new();
    let functions = module.functions.iter().map(|(h, f)| (f, &info[h]));
    let entries = (module.entry_points.iter().enumerate())
        .map(|(i, ep)| (&ep.function, info.get_entry_point(i)));
    for (function, fun_info) in functions.chain(entries) {
        for (handle, expr) in function.expressions.iter() {
            let naga::Expression::Access { base, index } = *expr else {
                continue;
            };
            let constant = matches!(
                function.expressions[index],
                naga::Expression::Literal(_) | naga::Expression::Constant(_)
            );
            let base_ty = fun_info[base].ty.inner_with(&module.types);
            if !constant && matches!(base_ty, naga::TypeInner::Array { .. }) {
                let name = function.name.clone().unwrap_or_default();
                found.push(format!("{name} (expression {})", handle.index()));
            }
        }
    }
    found
}

/// An array inside a value (a struct read from a buffer and passed on, a `let` array) indexed
/// by a variable makes the compiler copy the whole value to per-invocation memory first, at
/// every such access: on lavapipe a material's lobe table read so cost gallery's shading pass
/// 30%, a light's cube views 10% more (the saliency's small constant Sobel kernels, also
/// caught, measured no different once replaced by arithmetic). Index a buffer or a `var`
/// through its pointer, or select among constant indices.
#[test]
fn no_shader_indexes_an_array_value_with_a_variable() {
    let mut found = std::collections::BTreeSet::new();
    for decl in PASSES {
        let (module, info) = pass_module(decl);
        found.extend(variable_indexes_into_values(&module, &info));
    }
    assert!(found.is_empty(), "{found:?}");
}
