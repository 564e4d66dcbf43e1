use super::*;

fn hanging(strands: usize, nodes: usize) -> Vec<Vec<Vec3>> {
    (0..strands)
        .map(|s| {
            let x = -0.05 + 0.1 * s as f32 / (strands - 1).max(1) as f32;
            (0..nodes)
                .map(|i| {
                    Vec3::new(
                        x + 0.01 * (i as f32 * 0.4).sin(),
                        0.1 - 0.2 * i as f32 / (nodes - 1) as f32,
                        0.03,
                    )
                })
                .collect()
        })
        .collect()
}

fn pixel(p: &Pixmap, x: u32, y: u32) -> [u8; 3] {
    let c = p.pixel(x, y).unwrap();
    [c.red(), c.green(), c.blue()]
}

/// A lit collider's pixel: the fill's cool grey in some shade (blue above red); hair is warm.
fn solid(c: [u8; 3], style: &Style) -> bool {
    c[2] > c[0] && c != style.background
}

fn brightness(c: [u8; 3]) -> u32 {
    c.iter().map(|&v| u32::from(v)).sum()
}

#[test]
fn png_has_strand_pixels_where_strands_are_and_background_elsewhere() {
    let strands = vec![vec![Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.0, -0.5, 0.0)]];
    let style = Style {
        strand_width: 3.0,
        ..Style::default()
    };
    let camera = Camera::fit((Vec3::splat(-0.5), Vec3::splat(0.5)), View::Front, 200, 100);
    let png = render_png(&strands, &[], &camera, &style).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let decoded = Pixmap::decode_png(&png).unwrap();
    assert_eq!((decoded.width(), decoded.height()), (200, 100));
    // The vertical strand runs down the middle column; its top is root-coloured, its bottom tip-coloured.
    let (top, bottom) = (pixel(&decoded, 100, 12), pixel(&decoded, 100, 88));
    assert_ne!(top, style.background);
    assert_ne!(bottom, style.background);
    let darkness = |c: [u8; 3]| c.iter().map(|&v| u32::from(v)).sum::<u32>();
    assert!(
        darkness(top) < darkness(bottom),
        "root {top:?} should be darker than tip {bottom:?}"
    );
    // Away from it, only background.
    for (x, y) in [(20, 50), (180, 50), (60, 10), (150, 90)] {
        assert_eq!(pixel(&decoded, x, y), style.background, "at {x},{y}");
    }
}

#[test]
fn colliders_are_filled_and_hide_hair_behind_them() {
    let style = Style::default();
    let head = Shape::Sphere {
        centre: Vec3::ZERO,
        radius: 0.1,
    };
    // One strand behind the head (z < 0) and one in front, both crossing its centre.
    let behind = vec![Vec3::new(-0.2, 0.0, -0.2), Vec3::new(0.2, 0.0, -0.2)];
    let front = vec![Vec3::new(0.0, -0.2, 0.2), Vec3::new(0.0, 0.2, 0.2)];
    let camera = Camera::fit(
        (Vec3::splat(-0.25), Vec3::splat(0.25)),
        View::Front,
        100,
        100,
    );
    let p = render(&[behind, front], &[head], &camera, &style).unwrap();
    let (c, _) = camera.project(Vec3::new(0.05, 0.0, 0.0));
    let at = pixel(&p, c.x as u32, c.y as u32);
    assert!(solid(at, &style), "hair behind is hidden: {at:?}");
    let (c, _) = camera.project(Vec3::new(0.0, 0.05, 0.0));
    let at = pixel(&p, c.x as u32, c.y as u32);
    assert!(!solid(at, &style), "hair in front shows: {at:?}");
    // Outside the head's disc but on the hidden strand: strand pixels.
    let (c, _) = camera.project(Vec3::new(0.18, 0.0, 0.0));
    assert_ne!(pixel(&p, c.x as u32, c.y as u32), style.background);
}

#[test]
fn a_neck_in_the_head_plane_is_drawn_behind_the_head() {
    let style = Style::default();
    let head = Shape::Sphere {
        centre: Vec3::ZERO,
        radius: 0.1,
    };
    let neck = Shape::Capsule {
        a: Vec3::new(0.0, -0.05, 0.0),
        b: Vec3::new(0.0, -0.2, 0.0),
        radius: 0.04,
    };
    let camera = Camera::fit(
        (Vec3::splat(-0.25), Vec3::splat(0.25)),
        View::Front,
        200,
        200,
    );
    // Listed head first, as the scenes do: the head's chin outline must still show over the
    // neck, and the neck below the chin is filled.
    let p = render::<Vec<Vec3>>(&[], &[head, neck], &camera, &style).unwrap();
    let at = |q: Vec3| {
        let (c, _) = camera.project(q);
        pixel(&p, c.x as u32, c.y as u32)
    };
    // The head's dark outline shows over the neck's fill.
    let chin = at(Vec3::new(0.0, -0.1, 0.0));
    let neck = at(Vec3::new(0.0, -0.15, 0.0));
    assert!(solid(neck, &style), "neck: {neck:?}");
    assert!(
        brightness(chin) + 60 < brightness(neck),
        "chin outline {chin:?}, neck {neck:?}"
    );
}

#[test]
fn capsules_and_planes_are_drawn() {
    let style = Style::default();
    let capsule = Shape::Capsule {
        a: Vec3::new(-0.1, 0.0, 0.0),
        b: Vec3::new(0.1, 0.0, 0.0),
        radius: 0.02,
    };
    let floor = Shape::Plane {
        point: Vec3::new(0.0, -0.2, 0.0),
        normal: Vec3::Y,
    };
    let camera = Camera::fit(
        (Vec3::splat(-0.25), Vec3::splat(0.25)),
        View::Front,
        100,
        100,
    );
    let p = render::<Vec<Vec3>>(&[], &[capsule, floor], &camera, &style).unwrap();
    let at = |q: Vec3| {
        let (c, _) = camera.project(q);
        pixel(&p, c.x as u32, c.y as u32)
    };
    assert!(solid(at(Vec3::ZERO), &style), "{:?}", at(Vec3::ZERO));
    let cap = at(Vec3::new(0.105, 0.0, 0.0));
    assert!(solid(cap, &style), "round cap: {cap:?}");
    assert_eq!(at(Vec3::new(0.0, 0.1, 0.0)), style.background);
    assert_eq!(
        at(Vec3::new(0.0, -0.24, 0.0)),
        style.plane_fill,
        "below the floor"
    );
}

#[test]
fn cameras_fit_and_views_differ() {
    let strands = hanging(5, 10);
    let c = Camera::fit_frame(&strands, &[], View::Front, 400, 300);
    for p in strands.iter().flatten() {
        let (q, _) = c.project(*p);
        assert!(q.x >= 0.0 && q.x <= 400.0 && q.y >= 0.0 && q.y <= 300.0);
    }
    let reach = Camera::fit_reach(&strands, &[], View::Front, 400, 300);
    assert!(reach.scale < c.scale);
    let side = Camera::fit_frame(&strands, &[], View::Side, 400, 300);
    let a = render(&strands, &[], &c, &Style::default()).unwrap();
    let b = render(&strands, &[], &side, &Style::default()).unwrap();
    assert_ne!(a.data(), b.data());
    assert!(
        Camera { width: 0, ..c }.width == 0
            && render(&strands, &[], &Camera { width: 0, ..c }, &Style::default()).is_err()
    );
}

#[test]
fn gif_frames_decode_back() {
    let camera = Camera::fit_reach(&hanging(4, 8), &[], View::Front, 64, 48);
    let mut gif = GifWriter::new(Vec::new(), camera, Style::default(), 4).unwrap();
    for k in 0..3 {
        let mut s = hanging(4, 8);
        s.iter_mut().flatten().for_each(|p| p.x += 0.01 * k as f32);
        gif.add_frame(&s, &[]).unwrap();
    }
    assert_eq!(gif.frames(), 3);
    let bytes = gif.finish().unwrap();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(bytes.as_slice()).unwrap();
    let mut frames = 0;
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        assert_eq!((frame.width, frame.height, frame.delay), (64, 48, 4));
        frames += 1;
    }
    assert_eq!(frames, 3);
}

#[test]
fn views_parse_from_their_names() {
    assert_eq!("Side".parse::<View>(), Ok(View::Side));
    assert!("diagonal".parse::<View>().is_err());
}
