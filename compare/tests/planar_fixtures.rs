//! Golden fixtures for ring soups under fill rules, GeoJSON-role polygons and boolean operations
//! on such shapes: `tests/fixtures/planar/*.json`, in the spirit of i_overlay's test folder.
//!
//! Each fixture holds its input and the expected output as contours, derived by hand (every
//! vertex of these inputs and outputs is a lattice point, so areas are exact). The test checks
//! the expectation itself against two independent references, i_overlay and clipper2 (same fill
//! rule, same operation), and then our result against the expectation: same area, symmetric
//! difference of zero area (measured by i_overlay), and a valid shape.
//!
//! Format (a JSON object):
//! - `"kind": "fill"`: `"rings"` (arrays of `[x, y]`), `"expected"`: an object from fill-rule
//!   name (`EvenOdd`, `NonZero`, `Positive`, `Negative`) to contours;
//! - `"kind": "polygon"`: `"rings"` with GeoJSON roles (first exterior, others holes), and
//!   `"expected"` contours;
//! - `"kind": "multipolygon"`: `"polygons"` (each a list of rings, holes not used here), and
//!   `"expected"` contours;
//! - `"kind": "boolean"`: `"rule"`, operands `"a"` and `"b"` as ring soups under that rule, and
//!   `"expected"`: an object from operation (`intersection`, `union`, `difference`, `xor`) to
//!   contours.

// The crate's shared test helpers (generators, text format), from the package next door.
#[path = "../../tests/support/mod.rs"]
mod support;

use std::collections::BTreeMap;

use arealight::glam::DVec2;
use arealight::planar::{BoolOp, FillRule, Shape, boolean};
use arealight_compare::*;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::simplify::SimplifyShape;
use i_overlay::float::single::SingleFloatOverlay;
use support::planar::*;

/// A JSON value: just what the fixtures use.
#[derive(Debug, Clone)]
enum Json {
    Null,
    Bool(bool),
    Num(f64),
    Str(String),
    Arr(Vec<Json>),
    Obj(BTreeMap<String, Json>),
}

/// A small recursive-descent JSON reader (RFC 8259 without `\u` escapes, which the fixtures do
/// not use).
struct Reader<'a> {
    s: &'a [u8],
    i: usize,
}

impl Reader<'_> {
    fn parse(text: &str) -> Result<Json, String> {
        let mut r = Reader {
            s: text.as_bytes(),
            i: 0,
        };
        let v = r.value()?;
        r.ws();
        if r.i != r.s.len() {
            return Err(format!("trailing characters at byte {}", r.i));
        }
        Ok(v)
    }

    fn ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn eat(&mut self, c: u8) -> Result<(), String> {
        self.ws();
        if self.s.get(self.i) == Some(&c) {
            self.i += 1;
            Ok(())
        } else {
            Err(format!("expected '{}' at byte {}", c as char, self.i))
        }
    }

    fn value(&mut self) -> Result<Json, String> {
        self.ws();
        match self.s.get(self.i) {
            Some(b'{') => {
                self.i += 1;
                let mut m = BTreeMap::new();
                self.ws();
                if self.s.get(self.i) == Some(&b'}') {
                    self.i += 1;
                    return Ok(Json::Obj(m));
                }
                loop {
                    self.ws();
                    let Json::Str(k) = self.value()? else {
                        return Err(format!("object key must be a string at byte {}", self.i));
                    };
                    self.eat(b':')?;
                    let v = self.value()?;
                    m.insert(k, v);
                    self.ws();
                    match self.s.get(self.i) {
                        Some(b',') => self.i += 1,
                        Some(b'}') => {
                            self.i += 1;
                            return Ok(Json::Obj(m));
                        }
                        _ => return Err(format!("expected ',' or '}}' at byte {}", self.i)),
                    }
                }
            }
            Some(b'[') => {
                self.i += 1;
                let mut v = Vec::new();
                self.ws();
                if self.s.get(self.i) == Some(&b']') {
                    self.i += 1;
                    return Ok(Json::Arr(v));
                }
                loop {
                    v.push(self.value()?);
                    self.ws();
                    match self.s.get(self.i) {
                        Some(b',') => self.i += 1,
                        Some(b']') => {
                            self.i += 1;
                            return Ok(Json::Arr(v));
                        }
                        _ => return Err(format!("expected ',' or ']' at byte {}", self.i)),
                    }
                }
            }
            Some(b'"') => {
                self.i += 1;
                let mut out = String::new();
                loop {
                    match self.s.get(self.i) {
                        None => return Err("unterminated string".into()),
                        Some(b'"') => {
                            self.i += 1;
                            return Ok(Json::Str(out));
                        }
                        Some(b'\\') => {
                            let c = *self.s.get(self.i + 1).ok_or("bad escape")?;
                            out.push(match c {
                                b'n' => '\n',
                                b't' => '\t',
                                b'"' | b'\\' | b'/' => c as char,
                                _ => return Err(format!("unsupported escape at byte {}", self.i)),
                            });
                            self.i += 2;
                        }
                        Some(_) => {
                            // Copy one UTF-8 character.
                            let start = self.i;
                            self.i += 1;
                            while self.i < self.s.len() && (self.s[self.i] & 0xC0) == 0x80 {
                                self.i += 1;
                            }
                            out.push_str(std::str::from_utf8(&self.s[start..self.i]).unwrap());
                        }
                    }
                }
            }
            Some(b't') if self.s[self.i..].starts_with(b"true") => {
                self.i += 4;
                Ok(Json::Bool(true))
            }
            Some(b'f') if self.s[self.i..].starts_with(b"false") => {
                self.i += 5;
                Ok(Json::Bool(false))
            }
            Some(b'n') if self.s[self.i..].starts_with(b"null") => {
                self.i += 4;
                Ok(Json::Null)
            }
            Some(c) if *c == b'-' || c.is_ascii_digit() => {
                let start = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_digit() || b"+-.eE".contains(&self.s[self.i]))
                {
                    self.i += 1;
                }
                let t = std::str::from_utf8(&self.s[start..self.i]).unwrap();
                t.parse()
                    .map(Json::Num)
                    .map_err(|e| format!("bad number {t:?}: {e}"))
            }
            _ => Err(format!("unexpected input at byte {}", self.i)),
        }
    }
}

impl Json {
    fn get(&self, k: &str) -> &Json {
        match self {
            Json::Obj(m) => m.get(k).unwrap_or_else(|| panic!("missing key {k:?}")),
            _ => panic!("not an object"),
        }
    }

    fn str(&self) -> &str {
        match self {
            Json::Str(s) => s,
            _ => panic!("not a string: {self:?}"),
        }
    }

    fn arr(&self) -> &[Json] {
        match self {
            Json::Arr(v) => v,
            _ => panic!("not an array: {self:?}"),
        }
    }

    fn entries(&self) -> impl Iterator<Item = (&String, &Json)> {
        match self {
            Json::Obj(m) => m.iter(),
            _ => panic!("not an object"),
        }
    }

    fn point(&self) -> DVec2 {
        match self.arr() {
            [Json::Num(x), Json::Num(y)] => DVec2::new(*x, *y),
            other => panic!("not a point: {other:?}"),
        }
    }

    fn rings(&self) -> Vec<Vec<DVec2>> {
        self.arr()
            .iter()
            .map(|r| r.arr().iter().map(Json::point).collect())
            .collect()
    }
}

#[test]
fn json_reader_reads_what_the_fixtures_use() {
    let v =
        Reader::parse(r#" {"a": [1, -2.5e1, [3]], "b": "x\"y", "c": true, "d": null, "e": {}} "#)
            .unwrap();
    match v.get("a").arr() {
        [Json::Num(a), Json::Num(b), Json::Arr(c)] => {
            assert_eq!((*a, *b, c.len()), (1.0, -25.0, 1));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(v.get("b").str(), "x\"y");
    assert!(matches!(v.get("c"), Json::Bool(true)));
    assert!(matches!(v.get("d"), Json::Null));
    assert!(Reader::parse("[1, 2").is_err());
    assert!(Reader::parse("{\"a\" 1}").is_err());
    assert!(Reader::parse("[1] x").is_err());
}

fn rule_named(name: &str) -> FillRule {
    match name {
        "EvenOdd" => FillRule::EvenOdd,
        "NonZero" => FillRule::NonZero,
        "Positive" => FillRule::Positive,
        "Negative" => FillRule::Negative,
        _ => panic!("unknown fill rule {name:?}"),
    }
}

fn op_named(name: &str) -> BoolOp {
    match name {
        "intersection" => BoolOp::Intersection,
        "union" => BoolOp::Union,
        "difference" => BoolOp::Difference,
        "xor" => BoolOp::Xor,
        _ => panic!("unknown operation {name:?}"),
    }
}

fn io_rule(rule: FillRule) -> i_overlay::core::fill_rule::FillRule {
    use i_overlay::core::fill_rule::FillRule as F;
    match rule {
        FillRule::EvenOdd => F::EvenOdd,
        FillRule::NonZero => F::NonZero,
        FillRule::Positive => F::Positive,
        FillRule::Negative => F::Negative,
    }
}

fn clip_rule(rule: FillRule) -> clipper2::FillRule {
    match rule {
        FillRule::EvenOdd => clipper2::FillRule::EvenOdd,
        FillRule::NonZero => clipper2::FillRule::NonZero,
        FillRule::Positive => clipper2::FillRule::Positive,
        FillRule::Negative => clipper2::FillRule::Negative,
    }
}

fn paths(rings: &[Vec<DVec2>]) -> IPaths {
    rings
        .iter()
        .map(|r| r.iter().map(|p| [p.x, p.y]).collect())
        .collect()
}

fn clipper_paths(rings: &[Vec<DVec2>]) -> clipper2::Paths<Fine> {
    let v: Vec<Vec<(f64, f64)>> = rings
        .iter()
        .map(|r| r.iter().map(|p| (p.x, p.y)).collect())
        .collect();
    v.into()
}

/// Area of the region bounded by non-overlapping contours (outer counter-clockwise, holes
/// clockwise), as expected outputs are written.
fn contours_area(c: &[Vec<DVec2>]) -> f64 {
    paths(c).iter().map(|r| ring_area(r)).sum()
}

/// Area of the symmetric difference of two regions given as contours, by i_overlay (even-odd
/// fill on each side, as both are non-overlapping contour sets).
fn xor_area(a: &IPaths, b: &IPaths) -> f64 {
    ioverlay_area(&a.overlay_as::<i64>(
        b,
        OverlayRule::Xor,
        i_overlay::core::fill_rule::FillRule::EvenOdd,
    ))
}

/// The reference results of one check: i_overlay's region and clipper2's area.
struct References {
    ioverlay: IPaths,
    clipper_area: f64,
}

/// Checks `expected` against both references, then `ours` against `expected`.
fn compare(name: &str, expected: &[Vec<DVec2>], refs: References, ours: &Shape) {
    let want = contours_area(expected);
    let exp = paths(expected);
    let tol = 1e-9 * want.max(1.0);
    let d = xor_area(&exp, &refs.ioverlay);
    assert!(
        d <= tol,
        "{name}: the expected output differs from i_overlay's by area {d}"
    );
    assert!(
        (refs.clipper_area - want).abs() <= tol,
        "{name}: expected area {want}, clipper2 {}",
        refs.clipper_area
    );
    ours.validate()
        .unwrap_or_else(|e| panic!("{name}: invalid result {e}\n{ours:?}"));
    assert!(
        (ours.area() - want).abs() <= tol,
        "{name}: area {} vs expected {want}\n{ours:?}",
        ours.area()
    );
    let d = xor_area(&exp, &to_paths(ours));
    assert!(
        d <= tol,
        "{name}: differs from the expected output by area {d}\n{ours:?}"
    );
}

/// Rings turned counter-clockwise (for the references, which read GeoJSON holes by
/// orientation); the fixtures' holes are simple rings.
fn ccw(rings: &[Vec<DVec2>]) -> Vec<Vec<DVec2>> {
    rings
        .iter()
        .map(|r| {
            let mut r = r.clone();
            if ring_area(&paths(std::slice::from_ref(&r))[0]) < 0.0 {
                r.reverse();
            }
            r
        })
        .collect()
}

fn run_fixture(name: &str, f: &Json) -> usize {
    let mut checks = 0;
    match f.get("kind").str() {
        "fill" => {
            let rings = f.get("rings").rings();
            for (rule_name, exp) in f.get("expected").entries() {
                let rule = rule_named(rule_name);
                let refs = References {
                    ioverlay: rings_of(paths(&rings).simplify_shape_as::<i64>(io_rule(rule))),
                    clipper_area: clipper2::union(
                        clipper_paths(&rings),
                        clipper_paths(&[]),
                        clip_rule(rule),
                    )
                    .map(|p| p.signed_area().abs())
                    .unwrap(),
                };
                let ours = Shape::with_fill_rule(rings.clone(), rule)
                    .unwrap_or_else(|e| panic!("{name} {rule_name}: {e}"));
                compare(&format!("{name} {rule_name}"), &exp.rings(), refs, &ours);
                checks += 1;
            }
        }
        "polygon" => {
            let rings = f.get("rings").rings();
            let holes = ccw(&rings[1..]);
            let nz = i_overlay::core::fill_rule::FillRule::NonZero;
            let refs = References {
                ioverlay: rings_of(paths(&rings[..1]).overlay_as::<i64>(
                    &paths(&holes),
                    OverlayRule::Difference,
                    nz,
                )),
                clipper_area: clipper2::difference(
                    clipper_paths(&rings[..1]),
                    clipper_paths(&holes),
                    clipper2::FillRule::NonZero,
                )
                .map(|p| p.signed_area().abs())
                .unwrap(),
            };
            let ours =
                Shape::from_polygon_rings(rings.clone()).unwrap_or_else(|e| panic!("{name}: {e}"));
            compare(name, &f.get("expected").rings(), refs, &ours);
            checks += 1;
        }
        "multipolygon" => {
            let polygons: Vec<Vec<Vec<DVec2>>> =
                f.get("polygons").arr().iter().map(Json::rings).collect();
            let exteriors = ccw(&polygons.iter().map(|p| p[0].clone()).collect::<Vec<_>>());
            assert!(
                polygons.iter().all(|p| p.len() == 1),
                "{name}: holes unsupported here"
            );
            let refs = References {
                ioverlay: rings_of(
                    paths(&exteriors)
                        .simplify_shape_as::<i64>(i_overlay::core::fill_rule::FillRule::NonZero),
                ),
                clipper_area: clipper2::union(
                    clipper_paths(&exteriors),
                    clipper_paths(&[]),
                    clipper2::FillRule::NonZero,
                )
                .map(|p| p.signed_area().abs())
                .unwrap(),
            };
            let ours = Shape::from_multipolygon(polygons).unwrap_or_else(|e| panic!("{name}: {e}"));
            compare(name, &f.get("expected").rings(), refs, &ours);
            checks += 1;
        }
        "boolean" => {
            let rule = rule_named(f.get("rule").str());
            let (a, b) = (f.get("a").rings(), f.get("b").rings());
            let sa = Shape::with_fill_rule(a.clone(), rule).unwrap();
            let sb = Shape::with_fill_rule(b.clone(), rule).unwrap();
            for (op_name, exp) in f.get("expected").entries() {
                let op = op_named(op_name);
                let overlay_rule = match op {
                    BoolOp::Intersection => OverlayRule::Intersect,
                    BoolOp::Union => OverlayRule::Union,
                    BoolOp::Difference => OverlayRule::Difference,
                    BoolOp::Xor => OverlayRule::Xor,
                };
                let (ca, cb, cr) = (clipper_paths(&a), clipper_paths(&b), clip_rule(rule));
                let clipped = match op {
                    BoolOp::Intersection => clipper2::intersect(ca, cb, cr),
                    BoolOp::Union => clipper2::union(ca, cb, cr),
                    BoolOp::Difference => clipper2::difference(ca, cb, cr),
                    BoolOp::Xor => clipper2::xor(ca, cb, cr),
                };
                let refs = References {
                    ioverlay: rings_of(paths(&a).overlay_as::<i64>(
                        &paths(&b),
                        overlay_rule,
                        io_rule(rule),
                    )),
                    clipper_area: clipped.map(|p| p.signed_area().abs()).unwrap(),
                };
                let ours = boolean(&sa, &sb, op).unwrap_or_else(|e| panic!("{name}: {e}"));
                compare(&format!("{name} {op_name}"), &exp.rings(), refs, &ours);
                // The result is an operand again: combined with B it gives back what the set
                // algebra says, e.g. (A op B) | B and A | B cover the same area for op = union.
                check_all(&ours, &sb, 1e-9).unwrap_or_else(|e| panic!("{name} {op_name}: {e}"));
                checks += 1;
            }
        }
        other => panic!("{name}: unknown kind {other:?}"),
    }
    checks
}

/// i_overlay's shapes flattened into one list of contours.
fn rings_of(shapes: Vec<Vec<Vec<[f64; 2]>>>) -> IPaths {
    shapes.into_iter().flatten().collect()
}

#[test]
fn fixtures() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/planar");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "fixtures missing in {dir:?}");
    let mut checks = 0;
    for path in &files {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(path).unwrap();
        let f = Reader::parse(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
        checks += run_fixture(&name, &f);
    }
    println!("{} fixtures, {checks} checks", files.len());
}
