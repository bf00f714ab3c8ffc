//! Nodes: local transforms, the tree under the scene's roots, and the camera in use.

use super::{camera, Ctx, LoadError};
use crate::scene::{Local, Node};
use glam::{Mat4, Quat, Vec3};

/// The node tree as the scene will use it.
pub(super) struct Graph {
    pub nodes: Vec<Node>,
    pub roots: Vec<usize>,
    pub camera_node: Option<usize>,
}

pub(super) fn read(cx: &mut Ctx, doc: &gltf::Document, lights: usize) -> Result<Graph, LoadError> {
    let mut nodes = Vec::new();
    let mut first_camera = None;
    for n in doc.nodes() {
        let mut node = one(cx, &n)?;
        node.light = super::lights::of_node(cx, doc, n.index(), lights)?;
        if node.camera.is_some() && first_camera.is_none() {
            first_camera = Some(n.index());
        }
        nodes.push(node);
    }
    check_tree(cx, &nodes)?;
    let roots = roots(doc, &nodes);
    check_roots(cx, &nodes, &roots)?;
    // Only cameras reachable from the roots count.
    let reachable = reachable(&nodes, &roots);
    let camera_node = first_camera
        .filter(|&c| reachable[c])
        .or_else(|| (0..nodes.len()).find(|&i| reachable[i] && nodes[i].camera.is_some()));
    Ok(Graph {
        nodes,
        roots,
        camera_node,
    })
}

fn one(cx: &mut Ctx, n: &gltf::Node) -> Result<Node, LoadError> {
    let local = local(cx, n)?;
    let camera = match n.camera() {
        Some(c) => camera::read(cx, &c)?,
        None => None,
    };
    Ok(Node {
        name: n.name().unwrap_or("").to_string(),
        local,
        children: n.children().map(|c| c.index()).collect(),
        mesh: n.mesh().map(|m| m.index()),
        camera,
        light: None,
    })
}

fn local(cx: &Ctx, n: &gltf::Node) -> Result<Local, LoadError> {
    match n.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let m = Mat4::from_cols_array_2d(&matrix);
            if !m.is_finite() {
                return Err(cx.err(format!("node {} has a non-finite matrix", n.index())));
            }
            Ok(Local::Matrix(m))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let (t, r, s) = (
                Vec3::from(translation),
                Quat::from_array(rotation),
                Vec3::from(scale),
            );
            if !(t.is_finite() && r.is_finite() && s.is_finite()) {
                return Err(cx.err(format!("node {} has a non-finite transform", n.index())));
            }
            if r.length_squared() < 1e-12 {
                return Err(cx.err(format!(
                    "node {} has the rotation {r}, a zero quaternion, which is no rotation (glTF needs unit quaternions)",
                    n.index()
                )));
            }
            Ok(Local::Trs {
                translation: t,
                rotation: r.normalize(),
                scale: s,
            })
        }
    }
}

/// The default scene's root nodes, or else every node that is nobody's child.
fn roots(doc: &gltf::Document, nodes: &[Node]) -> Vec<usize> {
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => {
            let mut is_child = vec![false; nodes.len()];
            for n in nodes {
                for &c in &n.children {
                    is_child[c] = true;
                }
            }
            (0..nodes.len()).filter(|&i| !is_child[i]).collect()
        }
    }
}

fn reachable(nodes: &[Node], roots: &[usize]) -> Vec<bool> {
    let mut seen = vec![false; nodes.len()];
    let mut stack = roots.to_vec();
    while let Some(n) = stack.pop() {
        if !std::mem::replace(&mut seen[n], true) {
            stack.extend(nodes[n].children.iter());
        }
    }
    seen
}

/// glTF nodes form disjoint trees: one parent at most, no cycles (glTF 2.0 section 3.5.3).
/// A graph that shares children could instance a node along exponentially many paths.
fn check_tree(cx: &Ctx, nodes: &[Node]) -> Result<(), LoadError> {
    let mut parent = vec![None; nodes.len()];
    for (p, n) in nodes.iter().enumerate() {
        for &c in &n.children {
            if parent[c] == Some(p) {
                return Err(cx.err(format!(
                    "node {p} lists node {c} twice among its children; glTF nodes form trees"
                )));
            }
            if let Some(q) = parent[c].replace(p) {
                return Err(cx.err(format!(
                    "node {c} ('{}') is a child of node {q} and of node {p}; glTF nodes form trees, one parent each",
                    nodes[c].name
                )));
            }
        }
    }
    let tops: Vec<usize> = (0..nodes.len()).filter(|&i| parent[i].is_none()).collect();
    let seen = reachable(nodes, &tops);
    if let Some(c) = seen.iter().position(|&s| !s) {
        return Err(cx.err(format!(
            "node {c} ('{}') is in or under a cycle of children: no node without a parent leads to it",
            nodes[c].name
        )));
    }
    Ok(())
}

/// A scene's roots are distinct nodes without a parent, so every node is reached once.
fn check_roots(cx: &Ctx, nodes: &[Node], roots: &[usize]) -> Result<(), LoadError> {
    let mut is_root = vec![false; nodes.len()];
    for &r in roots {
        if std::mem::replace(&mut is_root[r], true) {
            return Err(cx.err(format!("the scene lists node {r} twice")));
        }
    }
    for (p, n) in nodes.iter().enumerate() {
        if let Some(&c) = n.children.iter().find(|&&c| is_root[c]) {
            return Err(cx.err(format!(
                "node {c} is a root of the scene and also a child of node {p}"
            )));
        }
    }
    Ok(())
}

/// EXT_mesh_gpu_instancing: a node whose extension lists per-instance TRANSLATION, ROTATION
/// and SCALE draws its mesh once per instance, each transformed by its own TRS before the
/// node's transform. Each instance becomes a child node of its own carrying the mesh (the
/// node itself no longer does), so every stage sees ordinary nodes.
pub(super) fn instancing(
    cx: &Ctx,
    doc: &gltf::Document,
    buffers: &super::buffers::Buffers,
    graph: &mut Graph,
) -> Result<(), LoadError> {
    const EXT: &str = "EXT_mesh_gpu_instancing";
    let json = doc.as_json();
    for n in 0..graph.nodes.len().min(json.nodes.len()) {
        let Some(ext) = json.nodes[n]
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(EXT))
        else {
            continue;
        };
        let Some(mesh) = graph.nodes[n].mesh else {
            continue;
        };
        let attrs = ext.get("attributes").and_then(|a| a.as_object());
        let read = |name: &str, width: usize| -> Result<Option<Vec<f32>>, LoadError> {
            let Some(i) = attrs.and_then(|a| a.get(name)) else {
                return Ok(None);
            };
            let acc = i
                .as_u64()
                .and_then(|i| doc.accessors().nth(i as usize))
                .ok_or_else(|| {
                    cx.err(format!(
                        "invalid glTF: node {n}'s {EXT} {name} is {i}, not an accessor"
                    ))
                })?;
            let what = format!("node {n}'s {EXT} {name}");
            if super::buffers::width(acc.dimensions()) != width {
                return Err(cx.err(format!(
                    "accessor {} ({what}) has {} components, not {width}",
                    acc.index(),
                    super::buffers::width(acc.dimensions())
                )));
            }
            super::buffers::floats(cx, buffers, &acc, &what).map(Some)
        };
        let t = read("TRANSLATION", 3)?;
        let r = read("ROTATION", 4)?;
        let s = read("SCALE", 3)?;
        let counts: Vec<usize> = [(&t, 3), (&r, 4), (&s, 3)]
            .iter()
            .filter_map(|(v, w)| v.as_ref().map(|v| v.len() / w))
            .collect();
        let Some(&count) = counts.first() else {
            continue;
        };
        if counts.iter().any(|&c| c != count) {
            return Err(cx.err(format!(
                "invalid glTF: node {n}'s {EXT} attributes have different counts {counts:?}"
            )));
        }
        let name = graph.nodes[n].name.clone();
        for i in 0..count {
            let v3 = |v: &Option<Vec<f32>>, d: Vec3| {
                v.as_ref()
                    .map_or(d, |v| Vec3::from_slice(&v[3 * i..3 * i + 3]))
            };
            let translation = v3(&t, Vec3::ZERO);
            let scale = v3(&s, Vec3::ONE);
            let rotation = r
                .as_ref()
                .map_or(Quat::IDENTITY, |r| Quat::from_slice(&r[4 * i..4 * i + 4]));
            if !(translation.is_finite() && scale.is_finite() && rotation.is_finite())
                || rotation.length_squared() < 1e-12
            {
                return Err(cx.err(format!(
                    "node {n}'s {EXT} instance {i} has a non-finite transform or a zero rotation"
                )));
            }
            graph.nodes.push(Node {
                name: format!("{name} (instance {i})"),
                local: Local::Trs {
                    translation,
                    rotation: rotation.normalize(),
                    scale,
                },
                children: Vec::new(),
                mesh: Some(mesh),
                camera: None,
                light: None,
            });
            let child = graph.nodes.len() - 1;
            graph.nodes[n].children.push(child);
        }
        graph.nodes[n].mesh = None;
    }
    Ok(())
}
