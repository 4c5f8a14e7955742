use super::*;
use drape_io::scene::MaterialSpec;

fn shipped() -> Shipped {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    Shipped::of(&root.join(SCENE)).unwrap()
}

#[test]
fn interpolation_inside_at_points_and_outside() {
    let p = [(-1.0, 2.0), (0.0, 4.0), (2.0, 0.0)];
    assert_eq!(interpolate(&p, -1.0), Some(2.0));
    assert_eq!(interpolate(&p, 2.0), Some(0.0));
    assert_eq!(interpolate(&p, -0.5), Some(3.0));
    assert_eq!(interpolate(&p, 1.5), Some(1.0));
    assert_eq!(interpolate(&p, -1.5), None);
    assert_eq!(interpolate(&p, 2.5), None);
    assert_eq!(interpolate(&[], 0.0), None);
}

fn outcome(max_shear: f64, profile: Vec<(f64, f64)>, draw_in: [f64; 3]) -> Outcome {
    Outcome {
        status: "completed".into(),
        wall_s: 1.0,
        cpu_s: 1.0,
        steps: 10,
        max_shear_deg: max_shear,
        max_shear_away_deg: max_shear - 8.0,
        draw_in,
        profile,
        added_mass_fraction: 0.0,
        implicit: None,
    }
}

#[test]
fn errors_against_a_reference() {
    let r = outcome(30.0, vec![(-2.0, 0.0), (2.0, 4.0)], [50.0, 50.0, 60.0]);
    // Profile points at −1 (ref 1) and 1 (ref 3), one outside the
    // reference's range (ignored): errors 1 and −1 → RMS 1.
    let mut o = outcome(
        29.5,
        vec![(-3.0, 9.0), (-1.0, 2.0), (1.0, 2.0)],
        [51.0, 49.5, 57.0],
    );
    o.max_shear_away_deg = 22.25;
    let [shear, away, rms, draw_in] = errors(&o, &r);
    assert!((shear - 0.5).abs() < 1e-12);
    assert!((away - 0.25).abs() < 1e-12);
    assert!((rms - 1.0).abs() < 1e-12);
    assert!((draw_in - 3.0).abs() < 1e-12);
    let mut failed = o.clone();
    failed.status = "failed: exploded".into();
    assert!(errors(&failed, &r).iter().all(|e| e.is_nan()));
}

#[test]
fn the_reference_key_follows_the_values_the_reference_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let scene = root.join(SCENE);
    let text = std::fs::read_to_string(&scene).unwrap();
    let (overrides, _) = plan(false, None, shipped()).unwrap();
    let key = |text: &str| reference_key(text, &scene, &overrides).unwrap();
    let as_shipped = key(&text);
    // Values the reference overrides, and comments: the same reference.
    let line = |prefix: &str, new: &str| -> String {
        let changed: Vec<&str> = text
            .lines()
            .map(|l| if l.starts_with(prefix) { new } else { l })
            .collect();
        assert_ne!(changed.join("\n"), text.trim_end(), "no line `{prefix}…`");
        changed.join("\n")
    };
    assert_eq!(
        key(&line("mass_scaling_dt", "mass_scaling_dt = 3e-4")),
        as_shipped
    );
    assert_eq!(key(&format!("# another comment\n{text}")), as_shipped);
    let finer = "blank = { width = 350, height = 350, cells = [50, 50] }";
    assert_eq!(key(&line("blank =", finer)), as_shipped);
    // A value it runs with: a new reference.
    assert_ne!(key(&line("friction =", "friction = 0.2")), as_shipped);
    let wider = "blank = { width = 360, height = 350, cells = [40, 40] }";
    assert_ne!(key(&line("blank =", wider)), as_shipped);
    // And another mesh for the reference itself.
    let (coarse, _) = plan(false, Some(30), shipped()).unwrap();
    assert_ne!(reference_key(&text, &scene, &coarse).unwrap(), as_shipped);
    // The material by its values: a card changes the key with its text.
    let dir = std::env::temp_dir().join(format!("drape-refkey-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut card = Material::preset("carbon-prepreg-2x2").unwrap();
    let with_card = |card: &Material, file: &str| {
        let path = dir.join(file);
        std::fs::write(&path, toml::to_string(card).unwrap()).unwrap();
        let named = format!("material = \"{}\"", path.display());
        key(&line("material =", &named))
    };
    let first = with_card(&card, "card.toml");
    assert_eq!(with_card(&card, "card.toml"), first);
    card.density *= 1.001;
    assert_ne!(with_card(&card, "card.toml"), first);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn rows_are_unique_and_one_is_shipped() {
    for quick in [false, true] {
        let (reference, rows) = plan(quick, None, shipped()).unwrap();
        assert!(!reference.is_empty());
        let mut names: Vec<&str> = rows.iter().map(|r| r.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), rows.len(), "duplicate row names");
        assert_eq!(
            rows.iter().filter(|r| r.default).count(),
            usize::from(!quick)
        );
    }
}

#[test]
fn material_overrides_make_a_valid_scene() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let scene = root.join(SCENE);
    for row in plan(false, None, shipped())
        .unwrap()
        .1
        .iter()
        .chain(&prony_plan(false).unwrap())
    {
        if row.optional {
            continue;
        }
        let s = Scene::from_file(&scene, &row.overrides)
            .unwrap_or_else(|e| panic!("row {}: {e}", row.name));
        let prony = match &s.spec.fabric.material {
            MaterialSpec::Inline(m) => m.resin.prony.clone(),
            MaterialSpec::Preset(_) => continue,
        };
        if row.name.contains("tau0.1") {
            // The preset's shortest relaxation time is 0.01 s.
            assert!((prony[0].tau - 0.001).abs() < 1e-15, "{prony:?}");
            assert_eq!(prony.len(), 6);
        } else if row.name.starts_with("elastic") {
            assert!(prony.is_empty());
        }
    }
}
