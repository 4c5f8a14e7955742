//! Assembling what the reader read: each instance a placed copy of its
//! part (or each part where it is, in a file without instances), labels
//! turned into indices, sets resolved in file order and named.

use std::collections::HashMap;

use super::{
    At, ImportError, ImportErrorKind, InpReader, InpShape, Member, Position, RawElement, RawMesh,
    ScopeKind,
};

/// One placed copy of a mesh: an instance (its part's scope and its own),
/// a part placed where it is, or the model level.
struct Placement {
    /// The instance's name (the part's, for a part placed as it is); None
    /// for the model level.
    name: Option<String>,
    scopes: Vec<usize>,
    position: Position,
    /// Where its label errors point: "part P", "the file".
    owner: String,
}

impl InpReader {
    /// The placed copies: every instance (its part's scope, then its own),
    /// or every part where it is when the file has no instance, and the
    /// model level last (its sets may name the instances' sets).
    fn placements(&self) -> Result<Vec<Placement>, ImportError> {
        let instances: Vec<usize> = (0..self.scopes.len())
            .filter(|&s| matches!(self.scopes[s].kind, ScopeKind::Instance { .. }))
            .collect();
        let mut out = Vec::new();
        if instances.is_empty() {
            for (s, scope) in self.scopes.iter().enumerate() {
                if matches!(scope.kind, ScopeKind::Part) {
                    out.push(Placement {
                        name: Some(scope.name.clone()),
                        scopes: vec![s],
                        position: Position::default(),
                        owner: format!("part {}", scope.name),
                    });
                }
            }
        }
        for &i in &instances {
            let scope = &self.scopes[i];
            let ScopeKind::Instance { part, position } = &scope.kind else {
                continue;
            };
            let Some(p) = self.scopes.iter().position(|s| {
                matches!(s.kind, ScopeKind::Part) && s.name.eq_ignore_ascii_case(part)
            }) else {
                let parts: Vec<&str> = self
                    .scopes
                    .iter()
                    .filter(|s| matches!(s.kind, ScopeKind::Part))
                    .map(|s| s.name.as_str())
                    .collect();
                return Err(self.err(
                    scope.at,
                    ImportErrorKind::UndefinedSet,
                    format!(
                        "instance {} is of part {part}, which the file does not define ({})",
                        scope.name,
                        if parts.is_empty() {
                            "it has no *PART".to_owned()
                        } else {
                            format!("its parts: {}", parts.join(", "))
                        }
                    ),
                ));
            };
            out.push(Placement {
                name: Some(scope.name.clone()),
                scopes: vec![p, i],
                position: position.clone(),
                owner: format!("part {part} (instance {})", scope.name),
            });
        }
        out.push(Placement {
            name: None,
            scopes: vec![0],
            position: Position::default(),
            owner: "the file".into(),
        });
        Ok(out)
    }

    /// Instances placed (only `only`, if given), labels → indices, sets
    /// resolved and named.
    pub(super) fn resolve(self, only: Option<&str>) -> Result<RawMesh, ImportError> {
        let mut placements = self.placements()?;
        if let Some(only) = only {
            let names: Vec<String> = placements.iter().filter_map(|p| p.name.clone()).collect();
            // The model level's sets may name the others: it goes too.
            placements.retain(|p| {
                p.name
                    .as_deref()
                    .is_some_and(|n| n.eq_ignore_ascii_case(only))
            });
            if placements.is_empty() {
                return Err(self.err(
                    At::default(),
                    ImportErrorKind::UndefinedSet,
                    format!(
                        "`instance = \"{only}\"`: the file has no such instance ({})",
                        if names.is_empty() {
                            "it has neither instances nor parts".to_owned()
                        } else {
                            format!("it has {}", names.join(", "))
                        }
                    ),
                ));
            }
        }
        let mut raw = RawMesh {
            files: self.files.clone(),
            instances: placements
                .iter()
                .filter(|p| p.scopes.len() == 2)
                .filter_map(|p| p.name.clone())
                .collect(),
            ..RawMesh::default()
        };
        // Per placement: label → global node and element index.
        let mut node_maps: Vec<HashMap<i64, u32>> = Vec::with_capacity(placements.len());
        let mut element_maps: Vec<HashMap<i64, usize>> = Vec::with_capacity(placements.len());
        // Every element's global nodes (lines and points too, for sets).
        let mut elements_nodes: Vec<Vec<u32>> = Vec::new();
        for p in &placements {
            let mut nodes: HashMap<i64, u32> = HashMap::new();
            let mut node_at: HashMap<i64, At> = HashMap::new();
            for &s in &p.scopes {
                for &(label, x, at) in &self.scopes[s].nodes {
                    if let Some(first) = node_at.get(&label) {
                        return Err(self.err(
                            at,
                            ImportErrorKind::Duplicate,
                            format!(
                                "node {label} is defined twice (first at {}:{})",
                                self.files[first.file].display(),
                                first.line
                            ),
                        ));
                    }
                    let i = u32::try_from(raw.x0.len()).map_err(|_| {
                        self.err(at, ImportErrorKind::Unsupported, "more than 2³² nodes")
                    })?;
                    node_at.insert(label, at);
                    nodes.insert(label, i);
                    raw.x0.push(p.position.apply(&x));
                    raw.node_labels.push(label);
                }
            }
            let mut elements: HashMap<i64, usize> = HashMap::new();
            let mut element_at: HashMap<i64, At> = HashMap::new();
            for &s in &p.scopes {
                for e in &self.scopes[s].elements {
                    if let Some(before) = element_at.get(&e.label) {
                        return Err(self.err(
                            e.at,
                            ImportErrorKind::Duplicate,
                            format!(
                                "element {} is defined twice (first at {}:{})",
                                e.label,
                                self.files[before.file].display(),
                                before.line
                            ),
                        ));
                    }
                    let global = e
                        .node_labels
                        .iter()
                        .map(|&l| {
                            nodes.get(&l).copied().ok_or_else(|| {
                                self.err(
                                    e.at,
                                    ImportErrorKind::UndefinedNode,
                                    format!(
                                        "element {} uses node {l}, which {} does not define",
                                        e.label, p.owner
                                    ),
                                )
                            })
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    if matches!(e.shape, InpShape::Triangle | InpShape::Quad) {
                        let mut fixed = [0u32; 4];
                        fixed[..global.len()].copy_from_slice(&global);
                        raw.elements.push(RawElement {
                            label: e.label,
                            nodes: fixed,
                            len: global.len(),
                            file: e.at.file,
                            line: Some(e.at.line),
                        });
                    }
                    element_at.insert(e.label, e.at);
                    elements.insert(e.label, elements_nodes.len());
                    elements_nodes.push(global);
                }
            }
            node_maps.push(nodes);
            element_maps.push(elements);
        }

        // Sets, placement by placement, members in file order: a reference
        // to a set takes what it holds at that point.
        let named = placements.iter().filter(|p| p.name.is_some()).count();
        let by_instance = |name: &str| {
            placements.iter().position(|p| {
                p.scopes.len() == 2
                    && p.name
                        .as_deref()
                        .is_some_and(|n| n.eq_ignore_ascii_case(name))
            })
        };
        let mut nsets: HashMap<(usize, String), Vec<u32>> = HashMap::new();
        let mut elsets: HashMap<(usize, String), Vec<usize>> = HashMap::new();
        for (u, p) in placements.iter().enumerate() {
            for &s in &p.scopes {
                for m in &self.scopes[s].set_members {
                    let at = m.at;
                    let set_name = || {
                        let sets = if m.elements {
                            &self.scopes[s].elsets
                        } else {
                            &self.scopes[s].nsets
                        };
                        sets.iter()
                            .find(|(k, _)| *k == m.key)
                            .map_or_else(|| m.key.clone(), |(_, n)| n.clone())
                    };
                    // Where the member's labels live.
                    let target = match &m.instance {
                        Some(i) => by_instance(i).ok_or_else(|| {
                            self.err(
                                at,
                                ImportErrorKind::UndefinedSet,
                                format!(
                                    "set {} names instance {i}, which the file does not define",
                                    set_name()
                                ),
                            )
                        })?,
                        None => u,
                    };
                    let owner = &placements[target].owner;
                    if m.elements {
                        let found: Vec<usize> = match &m.member {
                            Member::Label(l) => {
                                vec![*element_maps[target].get(l).ok_or_else(|| {
                                    self.err(
                                        at,
                                        ImportErrorKind::UndefinedElement,
                                        format!(
                                            "element set {} uses element {l}, which {owner} does \
                                             not define",
                                            set_name()
                                        ),
                                    )
                                })?]
                            }
                            Member::Range(first, last, step) => self.range(
                                &element_maps[target],
                                (*first, *last, *step),
                                at,
                                &set_name(),
                                "elements",
                            )?,
                            Member::Set(other) => lookup(&elsets, target, other, &by_instance)
                                .ok_or_else(|| self.undefined_set(at, other, "element"))?
                                .clone(),
                            Member::ElementSet(_) | Member::Created => Vec::new(),
                        };
                        elsets.entry((u, m.key.clone())).or_default().extend(found);
                    } else {
                        let found: Vec<u32> = match &m.member {
                            Member::Label(l) => {
                                vec![*node_maps[target].get(l).ok_or_else(|| {
                                    self.err(
                                    at,
                                    ImportErrorKind::UndefinedNode,
                                    format!(
                                        "node set {} uses node {l}, which {owner} does not define",
                                        set_name()
                                    ),
                                )
                                })?]
                            }
                            Member::Range(first, last, step) => self.range(
                                &node_maps[target],
                                (*first, *last, *step),
                                at,
                                &set_name(),
                                "nodes",
                            )?,
                            Member::Set(other) => lookup(&nsets, target, other, &by_instance)
                                .ok_or_else(|| self.undefined_set(at, other, "node"))?
                                .clone(),
                            Member::ElementSet(other) => {
                                lookup(&elsets, target, other, &by_instance)
                                    .ok_or_else(|| self.undefined_set(at, other, "element"))?
                                    .iter()
                                    .flat_map(|&e| elements_nodes[e].iter().copied())
                                    .collect()
                            }
                            Member::Created => Vec::new(),
                        };
                        nsets.entry((u, m.key.clone())).or_default().extend(found);
                    }
                }
            }
        }
        for (u, p) in placements.iter().enumerate() {
            // Several instances: a part's set S of instance I is I.S.
            let prefix = match &p.name {
                Some(n) if named > 1 => format!("{n}."),
                _ => String::new(),
            };
            for &s in &p.scopes {
                for (key, name) in &self.scopes[s].nsets {
                    let nodes = nsets.get(&(u, key.clone())).cloned().unwrap_or_default();
                    raw.node_sets
                        .entry(format!("{prefix}{name}"))
                        .or_default()
                        .extend(nodes);
                }
                for (key, name) in &self.scopes[s].elsets {
                    let nodes = elsets
                        .get(&(u, key.clone()))
                        .into_iter()
                        .flatten()
                        .flat_map(|&e| elements_nodes[e].iter().copied());
                    raw.node_sets
                        .entry(format!("elset:{prefix}{name}"))
                        .or_default()
                        .extend(nodes);
                }
            }
        }
        Ok(raw)
    }

    fn undefined_set(&self, at: At, name: &str, what: &str) -> ImportError {
        self.err(
            at,
            ImportErrorKind::UndefinedSet,
            format!("{what} set {name} is not defined before it is used here"),
        )
    }

    /// The defined labels of a GENERATE range, in label order. Labels the
    /// file does not define are skipped (a step over a sparse numbering),
    /// but a range that finds none is an error.
    fn range<T: Copy>(
        &self,
        index: &HashMap<i64, T>,
        (first, last, step): (i64, i64, i64),
        at: At,
        set: &str,
        what: &str,
    ) -> Result<Vec<T>, ImportError> {
        let span = (last as i128 - first as i128) / step as i128 + 1;
        let mut found: Vec<(i64, T)> = if span <= 4 * index.len() as i128 + 16 {
            (0..span as i64)
                .map(|k| first + k * step)
                .filter_map(|l| index.get(&l).map(|&v| (l, v)))
                .collect()
        } else {
            // A huge range: walk the defined labels instead of the range.
            index
                .iter()
                .filter(|&(&l, _)| {
                    l >= first && l <= last && (l as i128 - first as i128) % step as i128 == 0
                })
                .map(|(&l, &v)| (l, v))
                .collect()
        };
        if found.is_empty() {
            return Err(self.err(
                at,
                if what == "nodes" {
                    ImportErrorKind::UndefinedNode
                } else {
                    ImportErrorKind::UndefinedElement
                },
                format!(
                    "set {set}: GENERATE {first}, {last}, {step} names no {what} the file defines"
                ),
            ));
        }
        found.sort_unstable_by_key(|&(l, _)| l);
        Ok(found.into_iter().map(|(_, v)| v).collect())
    }
}

/// The set `name` as resolved so far: placement `target`'s, or
/// `INSTANCE.SET` of another placement.
fn lookup<'m, T>(
    sets: &'m HashMap<(usize, String), Vec<T>>,
    target: usize,
    name: &str,
    by_instance: &dyn Fn(&str) -> Option<usize>,
) -> Option<&'m Vec<T>> {
    let key = name.to_ascii_uppercase();
    sets.get(&(target, key.clone())).or_else(|| {
        let (instance, set) = key.split_once('.')?;
        sets.get(&(by_instance(instance)?, set.to_owned()))
    })
}
