//! The files of the ParaView output read back: a minimal XML tree (quick-xml) and the
//! VTK structures the tests check.

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;
use splinerod::Real;
use std::collections::HashMap;
use std::fs;
use std::path::Path;

// ---------------------------------------------------------------- a minimal XML tree

/// An XML element: name, attributes, text and children.
#[derive(Debug, Default)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) attrs: HashMap<String, String>,
    pub(super) text: String,
    pub(super) children: Vec<Element>,
}

impl Element {
    /// An element with the name and attributes of a start tag.
    pub(super) fn from_start(e: &BytesStart<'_>) -> Self {
        let utf8 = |bytes: &[u8]| String::from_utf8(bytes.to_vec()).expect("UTF-8");
        let attrs = (e.attributes().map(|a| a.expect("attribute")))
            .map(|a| (utf8(a.key.as_ref()), utf8(&a.value)))
            .collect();
        let name = utf8(e.name().as_ref());
        Self {
            name,
            attrs,
            ..Self::default()
        }
    }

    /// The value of attribute `key`, which must be present.
    pub(super) fn attr(&self, key: &str) -> &str {
        self.attrs
            .get(key)
            .unwrap_or_else(|| panic!("<{}> has no attribute {key}", self.name))
    }

    /// Attribute `key` parsed as a number.
    pub(super) fn number<T: std::str::FromStr>(&self, key: &str) -> T {
        let text = self.attr(key);
        text.parse()
            .unwrap_or_else(|_| panic!("<{}> {key}=\"{text}\" is not a number", self.name))
    }

    /// The only child named `name`.
    pub(super) fn child(&self, name: &str) -> &Element {
        let found: Vec<&Element> = self.children.iter().filter(|c| c.name == name).collect();
        assert_eq!(found.len(), 1, "<{}> must have one <{name}>", self.name);
        found[0]
    }

    /// The child `<DataArray>` with `Name="name"`.
    pub(super) fn array(&self, name: &str) -> &Element {
        let found: Vec<&Element> = (self.children.iter())
            .filter(|c| {
                c.name == "DataArray" && c.attrs.get("Name").map(String::as_str) == Some(name)
            })
            .collect();
        assert_eq!(found.len(), 1, "<{}> must have one array {name}", self.name);
        found[0]
    }

    /// The whitespace-separated values of a `<DataArray>`.
    pub(super) fn values<T: std::str::FromStr>(&self) -> Vec<T> {
        assert_eq!(self.name, "DataArray");
        assert_eq!(self.attr("format"), "ascii");
        (self.text.split_whitespace())
            .map(|v| v.parse().unwrap_or_else(|_| panic!("bad value {v:?}")))
            .collect()
    }
}

/// Parses `path` into its root element (the reader checks that end tags match).
pub(super) fn parse(path: &Path) -> Element {
    let text = fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = Reader::from_str(&text);
    reader.config_mut().trim_text(true);
    let mut stack = vec![Element::default()];
    let mut declared = false;
    loop {
        let event = reader
            .read_event()
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        match event {
            Event::Decl(_) => declared = true,
            Event::Start(e) => stack.push(Element::from_start(&e)),
            Event::Empty(e) => stack
                .last_mut()
                .unwrap()
                .children
                .push(Element::from_start(&e)),
            Event::End(_) => {
                let done = stack.pop().unwrap();
                stack.last_mut().expect("balanced").children.push(done);
            }
            Event::Text(t) => stack
                .last_mut()
                .unwrap()
                .text
                .push_str(&t.decode().unwrap()),
            Event::Eof => break,
            _ => {}
        }
    }
    assert!(declared, "{}: no XML declaration", path.display());
    let mut document = stack.pop().expect("document");
    assert!(stack.is_empty(), "{}: unclosed elements", path.display());
    assert_eq!(
        document.children.len(),
        1,
        "{}: one root element",
        path.display()
    );
    let root = document.children.pop().unwrap();
    assert_eq!(root.name, "VTKFile");
    assert_eq!(root.attr("version"), "0.1");
    assert_eq!(root.attr("byte_order"), "LittleEndian");
    root
}

// ------------------------------------------------------------- VTK files, checked

/// One `.vtp` file, checked for internal consistency.
#[derive(Debug)]
pub(super) struct PolyData {
    pub(super) time: Real,
    pub(super) step: usize,
    pub(super) points: Vec<[Real; 3]>,
    /// `(first, end)` point ranges of the polylines.
    pub(super) lines: Vec<(usize, usize)>,
    pub(super) arrays: HashMap<String, Vec<Real>>,
    pub(super) scalars: String,
}

impl PolyData {
    /// Reads and checks `path`.
    pub(super) fn read(path: &Path) -> Self {
        let root = parse(path);
        assert_eq!(root.attr("type"), "PolyData");
        let poly = root.child("PolyData");
        let field = poly.child("FieldData");
        let time: Vec<Real> = field.array("TimeValue").values();
        let step: Vec<usize> = field.array("step").values();
        assert_eq!((time.len(), step.len()), (1, 1));
        let piece = poly.child("Piece");
        for zero in ["NumberOfVerts", "NumberOfStrips", "NumberOfPolys"] {
            assert_eq!(piece.attr(zero), "0");
        }
        let n: usize = piece.number("NumberOfPoints");
        let points = read_points(piece.child("Points"), n);
        let lines = read_lines(piece.child("Lines"), piece.number("NumberOfLines"), n);
        let point_data = piece.child("PointData");
        let mut arrays = HashMap::new();
        for array in &point_data.children {
            assert_eq!(array.attr("type"), "Float64");
            let values: Vec<Real> = array.values();
            assert_eq!(
                values.len(),
                n,
                "{}: one value per point",
                array.attr("Name")
            );
            arrays.insert(array.attr("Name").to_string(), values);
        }
        let scalars = point_data.attr("Scalars").to_string();
        assert!(arrays.contains_key(&scalars), "Scalars names an array");
        Self {
            time: time[0],
            step: step[0],
            points,
            lines,
            arrays,
            scalars,
        }
    }

    /// The point-data array `name`.
    pub(super) fn values(&self, name: &str) -> &[Real] {
        self.arrays
            .get(name)
            .unwrap_or_else(|| panic!("no array {name}"))
    }
}

/// The coordinates of `<Points>`: exactly `n` triples.
pub(super) fn read_points(points: &Element, n: usize) -> Vec<[Real; 3]> {
    let array = points.child("DataArray");
    assert_eq!(array.attr("type"), "Float64");
    assert_eq!(array.attr("NumberOfComponents"), "3");
    let xyz: Vec<Real> = array.values();
    assert_eq!(xyz.len(), 3 * n, "NumberOfPoints matches the coordinates");
    xyz.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// The polylines of `<Lines>`: `count` contiguous runs covering all `n` points in order.
pub(super) fn read_lines(lines: &Element, count: usize, n: usize) -> Vec<(usize, usize)> {
    for name in ["connectivity", "offsets"] {
        assert_eq!(lines.array(name).attr("type"), "Int64");
    }
    let connectivity: Vec<usize> = lines.array("connectivity").values();
    let offsets: Vec<usize> = lines.array("offsets").values();
    assert_eq!(connectivity, (0..n).collect::<Vec<_>>());
    assert_eq!(offsets.len(), count, "NumberOfLines matches the offsets");
    assert_eq!(offsets.last(), Some(&n));
    let starts = std::iter::once(0).chain(offsets.iter().copied());
    let runs: Vec<(usize, usize)> = starts.zip(offsets.iter().copied()).collect();
    assert!(runs.iter().all(|(a, b)| b > a), "non-empty polylines");
    runs
}

/// A `.pvd` collection: its `(timestep, file)` entries.
pub(super) fn read_collection(path: &Path) -> Vec<(Real, String)> {
    let root = parse(path);
    assert_eq!(root.attr("type"), "Collection");
    let collection = root.child("Collection");
    (collection.children.iter())
        .map(|d| {
            assert_eq!(d.name, "DataSet");
            assert_eq!(d.attr("part"), "0");
            (d.number("timestep"), d.attr("file").to_string())
        })
        .collect()
}
