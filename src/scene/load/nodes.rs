//! Nodes: local transforms, the tree under the scene's roots, and the camera in use.

use super::{Ctx, LoadError};
use crate::scene::{CameraDef, Local, Node};
use glam::{Mat4, Quat, Vec3};

/// The node tree as the scene will use it.
pub(super) struct Graph {
    pub nodes: Vec<Node>,
    pub roots: Vec<usize>,
    pub camera_node: Option<usize>,
}

pub(super) fn read(cx: &mut Ctx, doc: &gltf::Document) -> Result<Graph, LoadError> {
    let mut nodes = Vec::new();
    let mut first_camera = None;
    for n in doc.nodes() {
        let node = one(cx, &n)?;
        if node.camera.is_some() && first_camera.is_none() {
            first_camera = Some(n.index());
        }
        nodes.push(node);
    }
    let roots = roots(doc, &nodes);
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
    let camera = match n.camera().as_ref().map(|c| c.projection()) {
        Some(gltf::camera::Projection::Perspective(p)) => Some(CameraDef { yfov: p.yfov() }),
        Some(gltf::camera::Projection::Orthographic(_)) => {
            cx.warn("orthographic cameras are ignored");
            None
        }
        None => None,
    };
    Ok(Node {
        name: n.name().unwrap_or("").to_string(),
        local,
        children: n.children().map(|c| c.index()).collect(),
        mesh: n.mesh().map(|m| m.index()),
        camera,
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
