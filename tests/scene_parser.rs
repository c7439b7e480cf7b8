//! The scene parser refuses what it cannot read unambiguously:
//! trailing content, duplicate keys and material names, structs written as positional arrays.
//! Every error has a 1-based line:column in characters and the JSON path, worded
//! `FILE:LINE:COL: PATH: message` with a `help:` line. A UTF-8 byte order mark is accepted.

use crate::common::repo;
use hexray::scene::{MaterialDesc, Scene, SceneError};
use serde_json::{json, Value};
use std::path::Path;

const ROOM: &str = "scenes/tncg15_room.json";

fn room_text() -> String {
    std::fs::read_to_string(repo(ROOM)).unwrap()
}

fn room() -> Value {
    serde_json::from_str(&room_text()).unwrap()
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_json(text, Path::new("scene.json"))
}

fn refused(text: &str) -> SceneError {
    match parse(text) {
        Ok(_) => panic!("accepted"),
        Err(e) => e,
    }
}

/// The text of 1-based line `line`.
fn line(text: &str, line: usize) -> &str {
    text.lines().nth(line - 1).unwrap_or("")
}

/// The 1-based (line, column in characters) of the `n`th (0-based) occurrence of `needle`.
fn position_of(text: &str, needle: &str, n: usize) -> (usize, usize) {
    let at = text.match_indices(needle).nth(n).expect("needle").0;
    let before = &text[..at];
    let l = before.matches('\n').count() + 1;
    let c = before.rsplit('\n').next().unwrap().chars().count() + 1;
    (l, c)
}

/// Checks the one located wording: `scene.json:L:C: PATH: message` and a help line.
fn assert_wording(e: &SceneError) {
    let shown = e.to_string();
    let (l, c) = e.line_col.expect("a line and column");
    let mut prefix = format!("scene.json:{l}:{c}: ");
    if !e.path.is_empty() {
        prefix += &format!("{}: ", e.path);
    }
    assert!(shown.starts_with(&prefix), "{shown}");
    assert!(!e.message.is_empty(), "{shown}");
    assert!(
        shown.contains("\n  help: ") && !e.help.is_empty(),
        "{shown}"
    );
}

#[test]
fn trailing_content_after_the_scene_is_refused_where_it_starts() {
    let text = room_text();
    for tail in ["\n{}\n", "\nx", " ]", "\n\"more\""] {
        let broken = format!("{}{tail}", text.trim_end());
        let e = refused(&broken);
        assert_wording(&e);
        assert!(e.message.contains("content after the end"), "{e}");
        let start = text.trim_end().len() + tail.len() - tail.trim_start().len();
        let want = position_of(&broken[start..], tail.trim(), 0);
        let lines_before = broken[..start].matches('\n').count();
        let want = (
            want.0 + lines_before,
            if want.0 == 1 && lines_before == 0 {
                want.1 + broken[..start].chars().count()
            } else if want.0 == 1 {
                want.1 + broken[..start].rsplit('\n').next().unwrap().chars().count()
            } else {
                want.1
            },
        );
        assert_eq!(e.line_col, Some(want), "{tail:?}: {e}");
    }
}

#[test]
fn a_duplicate_material_name_is_refused_at_the_second() {
    let text = room_text();
    // A second "red", differently coloured, right after the first (serde kept the last).
    let second = "\"red\": {\"type\": \"diffuse\", \"albedo\": [0.1, 0.1, 0.1]},\n  \"red\": {";
    let broken = text.replacen("\"red\": {", second, 1);
    let e = refused(&broken);
    assert_wording(&e);
    assert_eq!(e.path, "materials.red");
    assert!(e.message.contains("duplicate material name `red`"), "{e}");
    assert_eq!(e.line_col, Some(position_of(&broken, "\"red\"", 1)), "{e}");
    // The first one's place is named.
    let (l, c) = position_of(&broken, "\"red\"", 0);
    assert!(e.message.contains(&format!("{l}:{c}")), "{e}");
}

#[test]
fn a_duplicate_key_written_with_an_escape_is_still_a_duplicate() {
    let text = room_text();
    let second =
        "\"red\": {\"type\": \"diffuse\", \"albedo\": [0.1, 0.1, 0.1]},\n  \"r\\u0065d\": {";
    let broken = text.replacen("\"red\": {", second, 1);
    let e = refused(&broken);
    assert_wording(&e);
    assert_eq!(e.path, "materials.red");
    assert_eq!(e.line_col, Some(position_of(&broken, "\"r\\u0065d\"", 0)));
}

#[test]
fn duplicate_keys_anywhere_are_refused_at_the_second() {
    let text = room_text();
    for (from, to, path, needle) in [
        (
            "\"vfov_deg\": 90.0,",
            "\"vfov_deg\": 90.0,\n  \"vfov_deg\": 45.0,",
            "camera.vfov_deg",
            "\"vfov_deg\": 45.0",
        ),
        (
            "\"name\": \"tncg15_room\",",
            "\"name\": \"tncg15_room\",\n \"name\": \"other\",",
            "name",
            "\"name\": \"other\"",
        ),
        (
            "\"type\": \"mirror\",",
            "\"type\": \"mirror\",\n   \"type\": \"mirror\",",
            "materials.mirror.type",
            "\"type\": \"mirror\"",
        ),
    ] {
        let broken = text.replacen(from, to, 1);
        assert_ne!(broken, text);
        let e = refused(&broken);
        assert_wording(&e);
        assert_eq!(e.path, path, "{e}");
        assert!(e.message.contains("duplicate key"), "{e}");
        let n = if path == "materials.mirror.type" {
            1
        } else {
            0
        };
        assert_eq!(e.line_col, Some(position_of(&broken, needle, n)), "{e}");
    }
}

#[test]
fn an_escaped_key_does_not_lose_the_location_of_a_validation_error() {
    let mut v = room();
    v["materials"]["red"]["albedo"][0] = json!(1.5);
    let text = serde_json::to_string_pretty(&v)
        .unwrap()
        .replacen("\"materials\"", "\"m\\u0061terials\"", 1)
        .replacen("\"albedo\"", "\"\\u0061lbedo\"", 100);
    let e = refused(&text);
    assert_wording(&e);
    assert_eq!(e.path, "materials.red.albedo[0]");
    assert!(line(&text, e.line_col.unwrap().0).contains("1.5"), "{e}");
}

/// The scene's fields in declaration order, as serde's positional form takes them.
fn positional(v: &Value) -> Value {
    let fields = [
        "name",
        "seed",
        "notes",
        "camera",
        "materials",
        "triangles",
        "spheres",
        "boxes",
        "meshes",
    ];
    let default = |f: &str| match f {
        "name" => json!(""),
        "seed" => Value::Null,
        "materials" => json!({}),
        _ => json!([]),
    };
    Value::Array(
        fields
            .iter()
            .map(|f| v.get(*f).cloned().unwrap_or_else(|| default(f)))
            .collect(),
    )
}

#[test]
fn the_positional_array_form_of_the_scene_and_its_objects_is_refused() {
    let v = room();
    let whole = serde_json::to_string_pretty(&positional(&v)).unwrap();
    let e = refused(&whole);
    assert_wording(&e);
    assert_eq!(e.line_col, Some((1, 1)));
    assert!(e.message.contains("expected an object"), "{e}");

    // The camera as [eye, look_at, up, vfov_deg].
    let mut cam = v.clone();
    let c = &v["camera"];
    cam["camera"] = json!([c["eye"], c["look_at"], c["up"], c["vfov_deg"]]);
    let text = serde_json::to_string_pretty(&cam).unwrap();
    let e = refused(&text);
    assert_wording(&e);
    assert_eq!(e.path, "camera");
    assert!(
        line(&text, e.line_col.unwrap().0).contains("\"camera\""),
        "{e}"
    );
    assert!(e.message.contains("expected an object"), "{e}");

    // A triangle as [v, material] and a material as [type, albedo].
    let mut tri = v.clone();
    let t = v["triangles"][4].clone();
    tri["triangles"][4] = json!([t["v"], t["material"]]);
    let e = refused(&serde_json::to_string_pretty(&tri).unwrap());
    assert_eq!(e.path, "triangles[4]", "{e}");
    let mut mat = v.clone();
    mat["materials"]["red"] = json!(["diffuse", [0.75, 0.15, 0.15]]);
    let e = refused(&serde_json::to_string_pretty(&mat).unwrap());
    assert_eq!(e.path, "materials.red", "{e}");
    assert!(e.message.contains("expected an object"), "{e}");
}

#[test]
fn a_byte_order_mark_is_accepted_and_positions_stay_those_an_editor_shows() {
    let text = room_text();
    let with_bom = format!("\u{feff}{text}");
    let scene = parse(&with_bom).unwrap_or_else(|e| panic!("{e}"));
    let plain = parse(&text).unwrap();
    assert_eq!(scene.desc.triangles.len(), plain.desc.triangles.len());

    let broken = text.replacen("\"vfov_deg\": 90.0,", "\"vfov_deg\": 90.0,,", 1);
    let e = parse(&broken).unwrap_err();
    let e_bom = parse(&format!("\u{feff}{broken}")).unwrap_err();
    assert_eq!(e.line_col, e_bom.line_col);
    assert_eq!(
        e.line_col,
        Some(position_of(&broken, ",,", 0)).map(|(l, c)| (l, c + 1))
    );
}

#[test]
fn an_error_in_a_material_field_points_at_the_field() {
    for (field, value, message) in [
        ("albedo", json!("grey"), "invalid type"),
        ("albedo", json!([0.5, 0.5]), "invalid length"),
        (
            "reflectance",
            json!([1, 1, 1]),
            "unknown field `reflectance`",
        ),
    ] {
        let mut v = room();
        v["materials"]["red"][field] = value;
        let text = serde_json::to_string_pretty(&v).unwrap();
        let e = refused(&text);
        assert_wording(&e);
        assert_eq!(e.path, format!("materials.red.{field}"), "{e}");
        assert!(e.message.contains(message), "{e}");
        let (l, _) = e.line_col.unwrap();
        assert!(
            line(&text, l).contains(&format!("\"{field}\"")),
            "{field}: line {l} is `{}`: {e}",
            line(&text, l)
        );
    }
    // A material without its kind's field, and with no type.
    let mut v = room();
    v["materials"]["red"]
        .as_object_mut()
        .unwrap()
        .remove("albedo");
    let e = refused(&serde_json::to_string_pretty(&v).unwrap());
    assert_eq!(e.path, "materials.red");
    assert!(e.message.contains("missing field `albedo`"), "{e}");
    let mut v = room();
    v["materials"]["red"]
        .as_object_mut()
        .unwrap()
        .remove("type");
    let e = refused(&serde_json::to_string_pretty(&v).unwrap());
    assert!(e.message.contains("missing field `type`"), "{e}");
    // The unmodified room's material kinds still read.
    let scene = parse(&room_text()).unwrap();
    assert!(matches!(
        scene.desc.materials["light"],
        MaterialDesc::Emitter {
            one_sided: true,
            ..
        }
    ));
}

#[test]
fn columns_are_1_based_and_count_characters() {
    // serde_json counted bytes, and gave column 0 at the start of a line.
    let text = "{\n  \"name\": \"éàü\", x\n}";
    let e = refused(text);
    assert_wording(&e);
    assert_eq!(e.line_col, Some(position_of(text, "x", 0)), "{e}");
    // The end of a file that ends with a line break.
    let e = refused("{\n");
    assert_wording(&e);
    assert_eq!(e.line_col, Some((2, 1)), "{e}");
    let e = refused("");
    assert_eq!(e.line_col, Some((1, 1)), "{e}");
}

#[test]
fn a_validation_error_on_a_defaulted_field_is_located_at_its_parent() {
    // No triangles, no spheres: "no emitter" concerns a field absent from the file.
    let mut v = room();
    let o = v.as_object_mut().unwrap();
    o.remove("triangles");
    o.remove("spheres");
    o.remove("boxes");
    let e = refused(&serde_json::to_string_pretty(&v).unwrap());
    assert_wording(&e);
}
