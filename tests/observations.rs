//! Observation files for parameter identification (#48): the three kinds told apart by
//! their columns, an optional `sigma`, and every bad value named by file, line and
//! column.

use splinerod::fit::{ObservationFile, ObservationKind};
use splinerod::Error;

fn parsed(text: &str) -> Result<ObservationFile, Error> {
    ObservationFile::parse("obs.csv", text)
}

/// The message and the (line, column) of a rejected file.
fn rejected(text: &str) -> (String, (usize, usize)) {
    match parsed(text) {
        Err(
            e @ Error::Parse {
                position: Some(p), ..
            },
        ) => (e.to_string(), p),
        other => panic!("not refused with a position: {other:?}"),
    }
}

#[test]
fn the_three_kinds_are_read_by_their_columns() {
    let markers = parsed("t,s,x,y,z\n,0.25,0.1,-0.2,0\n,0.5, 0.2 ,-0.3,0\n").expect("markers");
    assert_eq!(markers.kind, ObservationKind::Marker);
    assert_eq!(markers.rows.len(), 2);
    assert_eq!(markers.residual_count(), 6);
    let r = &markers.rows[1];
    assert_eq!(
        (r.t, r.s, r.value, r.sigma, r.line),
        (None, Some(0.5), [0.2, -0.3, 0.0], 1.0, 3)
    );

    // Any column order, with sigma.
    let points = parsed("x,y,z,t,sigma\n1,2,3,0.5,1e-4\n").expect("points");
    assert_eq!(points.kind, ObservationKind::Point);
    assert_eq!(points.residual_count(), 1);
    let r = &points.rows[0];
    assert_eq!((r.t, r.value, r.sigma), (Some(0.5), [1.0, 2.0, 3.0], 1e-4));

    let forces = parsed("t,pin,fx,fy,fz\n1.0,1,0,-2.5,0\n").expect("forces");
    assert_eq!(forces.kind, ObservationKind::PinForce);
    assert_eq!(forces.rows[0].pin, Some(1));
    assert_eq!(forces.rows[0].value, [0.0, -2.5, 0.0]);
}

#[test]
fn bad_observations_are_named_by_line_and_column() {
    let cases = [
        ("t,s,x,y,z\n,0.5,nan,0,0\n", (2, 3), "`x`"),
        ("t,s,x,y,z\n,0.5,0,inf,0\n", (2, 4), "`y`"),
        ("t,s,x,y,z\n,0.5,0,0,\n", (2, 5), "`z`"),
        ("t,s,x,y,z\n,abc,0,0,0\n", (2, 2), "`s`"),
        ("t,s,x,y,z\n-1,0.5,0,0,0\n", (2, 1), "negative"),
        ("t,s,x,y,z,sigma\n,0.5,0,0,0,0\n", (2, 6), "`sigma`"),
        ("t,s,x,y,z,sigma\n,0.5,0,0,0,-1e-3\n", (2, 6), "`sigma`"),
        ("t,pin,fx,fy,fz\n,-1,0,0,0\n", (2, 2), "`pin`"),
        ("t,pin,fx,fy,fz\n,0.5,0,0,0\n", (2, 2), "`pin`"),
        ("t,s,x,y\n,0.5,0,0\n", (1, 1), "missing column `z`"),
        ("s,x,y,z\n0.5,0,0,0\n", (1, 1), "missing column `t`"),
        ("t,s,x,y,z,w\n,0.5,0,0,0,1\n", (1, 1), "unknown column `w`"),
        ("t,s,x,y,z\n", (1, 1), "no observations"),
        ("t,s,x,y,z\n,0.5,0,0\n", (2, 1), "field"),
    ];
    for (text, position, words) in cases {
        let (message, at) = rejected(text);
        assert_eq!(at, position, "{text:?}: {message}");
        assert!(
            message.contains("obs.csv") && message.contains(words),
            "{text:?}: {message}"
        );
    }
}

#[test]
fn observations_are_checked_against_the_scene() {
    let check = |text: &str, end: Option<f64>| parsed(text).expect("parsed").check(2, 1.5, end);
    assert!(check("t,s,x,y,z\n,1.5,0,0,0\n", None).is_ok());
    assert!(check("t,s,x,y,z\n0.5,1.5,0,0,0\n", Some(2.0)).is_ok());
    let refused = [
        ("t,s,x,y,z\n,1.6,0,0,0\n", None, "`s` = 1.6"),
        ("t,s,x,y,z\n0.5,0.5,0,0,0\n", None, "static"),
        ("t,s,x,y,z\n,0.5,0,0,0\n", Some(2.0), "need their time"),
        (
            "t,s,x,y,z\n2.5,0.5,0,0,0\n",
            Some(2.0),
            "after the run's end",
        ),
        ("t,pin,fx,fy,fz\n,2,0,0,0\n", None, "2 [[pins]]"),
    ];
    for (text, end, words) in refused {
        let message = check(text, end).expect_err(text).to_string();
        assert!(
            message.contains("obs.csv: line 2") && message.contains(words),
            "{text:?}: {message}"
        );
    }
}
