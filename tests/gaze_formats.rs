//! The eye-tracker exports people have: EyeLink ASC and Data Viewer reports, Tobii Pro Lab,
//! binocular files with --eye, delimiters and decimal commas, pupil units, and the ways such
//! files go wrong.

use fovea::gaze::formats::{parse, Eye, Format, FormatError, ParseOptions, PupilUnit};

fn opts() -> ParseOptions {
    ParseOptions::default()
}

fn with_eye(eye: Eye) -> ParseOptions {
    ParseOptions {
        eye: Some(eye),
        ..opts()
    }
}

/// A binocular ASC excerpt in edf2asc's layout: a blink on the right eye, a saccade on both.
const ASC_BINOCULAR: &str = "\
** CONVERTED FROM D:\\DATA\\S01.EDF using edfapi 4.2 Jan 01 2020
** DATE: Mon Jan  1 10:00:00 2024
MSG\t1000 DISPLAY_COORDS 0 0 1919 1079
START\t1000 \tLEFT\tRIGHT\tSAMPLES\tEVENTS
PRESCALER\t1
PUPIL\tAREA
SAMPLES\tGAZE\tLEFT\tRIGHT\tRATE\t 500.00\tTRACKING\tCR\tFILTER\t2
1000\t  960.0\t  540.0\t 1000.0\t  970.0\t  550.0\t 1100.0\t.....
1002\t  962.0\t  541.0\t 1004.0\t    .\t    .\t    0.0\t.....
SBLINK R 1004
1004\t  964.0\t  542.0\t 1008.0\t  200.0\t  900.0\t   50.0\t.....
EBLINK R 1004\t1004\t2
SSACC L  1006
1006\t 1200.0\t  542.0\t 1012.0\t 1210.0\t  552.0\t 1120.0\t.....
ESACC L  1006\t1008\t4\t  964.0\t  542.0\t 1300.0\t  542.0\t 8.00\t  400
1008\t 1300.0\t  542.0\t 1016.0\t 1310.0\t  552.0\t 1130.0\t.....
MSG\t1009 TRIAL_END
END\t1010 \tSAMPLES\tEVENTS\tRES\t  38.00\t  38.00
";

#[test]
fn asc_binocular_with_events_blinks_and_the_screen_from_display_coords() {
    let r = parse(ASC_BINOCULAR, &opts()).unwrap();
    assert_eq!(
        (r.format, r.eye, r.screen),
        (Format::EyelinkAsc, Some(Eye::Average), Some((1920, 1080)))
    );
    assert_eq!(r.samples.len(), 5);
    assert_eq!(r.samples[0].t_ms, 0.0);
    let [x, y] = r.samples[0].xy.unwrap();
    assert!(
        (x - 965.0 / 1920.0).abs() < 1e-12 && (y - 545.0 / 1080.0).abs() < 1e-12,
        "average"
    );
    // Right eye lost at 1002: the average is the left eye alone.
    assert_eq!(r.samples[1].xy, Some([962.0 / 1920.0, 541.0 / 1080.0]));
    // Right eye in a blink at 1004 (the tracker's 200,900 is the lid): left eye alone.
    assert_eq!(r.samples[2].xy, Some([964.0 / 1920.0, 542.0 / 1080.0]));
    assert_eq!(r.saccades, Some(vec![(6.0, 8.0)]));
    let right = parse(ASC_BINOCULAR, &with_eye(Eye::Right)).unwrap();
    assert_eq!((right.samples[1].xy, right.samples[2].xy), (None, None));
    assert_eq!(
        right.saccades,
        Some(vec![]),
        "the saccade event was the left eye's"
    );
    assert!(right.pupil_rule.unwrap().contains("√area"));
}

#[test]
fn asc_monocular_missing_values_and_diameter_pupils() {
    let text = "START\t5 \tRIGHT\tSAMPLES\tEVENTS\nPUPIL\tDIAMETER\nSAMPLES\tGAZE\tRIGHT\tRATE\t1000.00\n5\t100.0\t50.0\t800.0\t...\n6\t.\t.\t0.0\t...\n7\t110.0\t55.0\t1600.0\t...\n";
    let screen = ParseOptions {
        screen: Some((1000, 500)),
        ..opts()
    };
    let r = parse(text, &screen).unwrap();
    assert_eq!(r.eye, None, "monocular: no choice to make");
    assert_eq!(r.samples[0].xy, Some([0.1, 0.1]));
    assert_eq!((r.samples[1].xy, r.samples[1].pupil_mm), (None, None));
    assert!(r.pupil_rule.as_deref().unwrap().contains("arbitrary units"));
    // Median diameter of (800, 1600) is 1600 (upper median) ↦ 4 mm, so 800 ↦ 2 mm.
    assert!((r.samples[0].pupil_mm.unwrap() - 2.0).abs() < 1e-9);
    let left = ParseOptions {
        eye: Some(Eye::Left),
        ..screen.clone()
    };
    assert_eq!(
        parse(text, &left),
        Err(FormatError::EyeMissing {
            asked: Eye::Left,
            has: "right"
        })
    );
    // No screen in the file or on the command line: said, not guessed.
    assert_eq!(
        parse(text, &opts()),
        Err(FormatError::NeedsScreen(Format::EyelinkAsc))
    );
    let bad = "SAMPLES\tGAZE\tLEFT\n5\t100.0\tabc\t800.0\n";
    assert!(matches!(
        parse(bad, &screen),
        Err(FormatError::NotNumeric { line: 2, .. })
    ));
    let unsorted = "SAMPLES\tGAZE\tLEFT\n5\t1\t1\t1\n4\t1\t1\t1\n";
    assert!(matches!(
        parse(unsorted, &screen),
        Err(FormatError::Unsorted { line: 3, .. })
    ));
    assert_eq!(
        parse("SAMPLES\tGAZE\tLEFT\n", &screen),
        Err(FormatError::NoSamples)
    );
}

#[test]
fn data_viewer_reports_monocular_and_binocular() {
    let screen = ParseOptions {
        screen: Some((1920, 1080)),
        ..opts()
    };
    // A monocular (right-eye) report keeps the left columns, all ".".
    let mono = "RECORDING_SESSION_LABEL\tTRIAL_INDEX\tTIMESTAMP\tLEFT_GAZE_X\tLEFT_GAZE_Y\tLEFT_PUPIL_SIZE\tRIGHT_GAZE_X\tRIGHT_GAZE_Y\tRIGHT_PUPIL_SIZE\tRIGHT_IN_BLINK\tRIGHT_IN_SACCADE\n\
s1\t1\t2000\t.\t.\t.\t960.0\t540.0\t1000\t0\t0\n\
s1\t1\t2002\t.\t.\t.\t980.0\t540.0\t1000\t0\t1\n\
s1\t1\t2004\t.\t.\t.\t1000.0\t540.0\t1000\t0\t1\n\
s1\t1\t2006\t.\t.\t.\t3.0\t4.0\t0\t1\t0\n";
    let r = parse(mono, &screen).unwrap();
    assert_eq!((r.format, r.eye), (Format::DataViewer, Some(Eye::Right)));
    assert_eq!(r.samples[0].xy, Some([0.5, 0.5]));
    assert_eq!(r.samples[3].xy, None, "in a blink");
    assert_eq!(r.saccades, Some(vec![(2.0, 4.0)]));
    assert!(matches!(
        parse(
            mono,
            &ParseOptions {
                eye: Some(Eye::Left),
                ..screen.clone()
            }
        ),
        Err(FormatError::EyeMissing { .. })
    ));
    let bino = "TIMESTAMP\tLEFT_GAZE_X\tLEFT_GAZE_Y\tRIGHT_GAZE_X\tRIGHT_GAZE_Y\n10\t100\t100\t200\t300\n11\t.\t.\t200\t300\n";
    let r = parse(bino, &screen).unwrap();
    assert_eq!(r.eye, Some(Eye::Average));
    assert_eq!(r.samples[0].xy, Some([150.0 / 1920.0, 200.0 / 1080.0]));
    assert_eq!(
        r.samples[1].xy,
        Some([200.0 / 1920.0, 300.0 / 1080.0]),
        "one eye missing"
    );
    let left = parse(
        bino,
        &ParseOptions {
            eye: Some(Eye::Left),
            ..screen
        },
    )
    .unwrap();
    assert_eq!(left.samples[1].xy, None);
}

#[test]
fn tobii_pro_lab_with_decimal_commas_other_sensors_and_validity() {
    let text = "Recording timestamp [μs]\tSensor\tRecording resolution width\tRecording resolution height\tGaze point X\tGaze point Y\tGaze point left X\tGaze point left Y\tGaze point right X\tGaze point right Y\tPupil diameter left\tPupil diameter right\tValidity left\tValidity right\tEye movement type\n\
1000000\tEye Tracker\t1920\t1080\t960\t540\t950\t540\t970\t540\t3,5\t3,7\tValid\tValid\tFixation\n\
1000500\tMouse\t1920\t1080\t\t\t\t\t\t\t\t\t\t\t\n\
1008333\tEye Tracker\t1920\t1080\t960\t540\t950\t540\t970\t540\t3,4\t\tValid\tInvalid\tSaccade\n";
    let r = parse(text, &opts()).unwrap();
    assert_eq!(
        (r.format, r.eye, r.samples.len()),
        (Format::TobiiProLab, Some(Eye::Average), 2)
    );
    assert!((r.samples[1].t_ms - 8.333).abs() < 1e-9, "µs");
    assert_eq!(r.samples[0].xy, Some([0.5, 0.5]));
    assert!(
        (r.samples[0].pupil_mm.unwrap() - 3.6).abs() < 1e-9,
        "decimal commas, mm"
    );
    assert_eq!(
        r.samples[1].xy,
        Some([950.0 / 1920.0, 0.5]),
        "right eye invalid"
    );
    let saccades = r.saccades.unwrap();
    assert!(
        saccades.len() == 1 && (saccades[0].0 - 8.333).abs() < 1e-9,
        "{saccades:?}"
    );
}

#[test]
fn delimiters_decimal_commas_and_pupil_units_of_the_generic_format() {
    let text = "t_ms;x;y;pupil_mm\n0;0,25;0,5;1600\n1,5;0,75;0,5;400\n";
    let area = ParseOptions {
        pupil_unit: Some(PupilUnit::Area),
        ..opts()
    };
    let r = parse(text, &area).unwrap();
    assert_eq!(r.format, Format::Generic);
    assert_eq!(
        (r.samples[1].t_ms, r.samples[1].xy),
        (1.5, Some([0.75, 0.5]))
    );
    // Areas 1600 and 400: diameters 40 and 20, median (upper) 40 ↦ 4 mm, so 20 ↦ 2 mm.
    assert!((r.samples[1].pupil_mm.unwrap() - 2.0).abs() < 1e-9);
    let mm = parse("t_ms\tx\ty\tpupil_mm\n0\t0.5\t0.5\t3.5\n", &opts()).unwrap();
    assert_eq!(
        mm.samples[0].pupil_mm,
        Some(3.5),
        "tabs, decimal points, mm"
    );
    let quoted = parse("\"t_ms\",\"x\",\"y\"\n\"0\",\"0.5\",\"0.5\"\n", &opts()).unwrap();
    assert_eq!(quoted.samples[0].xy, Some([0.5, 0.5]));
}

#[test]
fn binocular_eyelink_csv_is_read_not_refused() {
    let text = "t_s,xpos_l,ypos_l,ps_l,xpos_r,ypos_r,ps_r\n0.000,100,100,1000,300,100,1000\n0.001,,,0,300,100,1000\n";
    let screen = ParseOptions {
        screen: Some((1000, 1000)),
        ..opts()
    };
    let r = parse(text, &screen).unwrap();
    assert_eq!((r.format, r.eye), (Format::Eyelink, Some(Eye::Average)));
    assert_eq!(r.samples[0].xy, Some([0.2, 0.1]));
    assert_eq!(r.samples[1].xy, Some([0.3, 0.1]));
}

#[test]
fn malformed_exports_get_clear_errors_and_never_panic() {
    let screen = ParseOptions {
        screen: Some((100, 100)),
        ..opts()
    };
    // Missing columns, ragged rows, stray quotes, an ASC line that is just a number.
    for text in [
        "TIMESTAMP\tLEFT_GAZE_X\n1\t2\n",
        "t_ms,x,y\n0,0.5\n1,0.5,0.5,9,9\n",
        "t_ms,x,y\n\"0,0.5,0.5\n",
        "SAMPLES GAZE LEFT\n7\n",
        "START 5 LEFT\n5 . . . ...\n",
        "\u{feff}t_ms,x,y\n0,0.5,0.5\n",
    ] {
        let _ = parse(text, &screen);
    }
    let e = parse("TIMESTAMP\tLEFT_GAZE_X\n1\t2\n", &screen).unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::MissingColumn { .. } | FormatError::Unknown { .. }
        ),
        "{e}"
    );
    let dup = parse(
        "TIMESTAMP\tRIGHT_GAZE_X\tRIGHT_GAZE_Y\n1\t2\t3\n1\t2\t3\n",
        &screen,
    );
    assert!(
        matches!(dup, Err(FormatError::Duplicate { line: 3, .. })),
        "{dup:?}"
    );
    let bom = parse("\u{feff}t_ms,x,y\n0,0.5,0.5\n", &screen).unwrap();
    assert_eq!(
        bom.samples.len(),
        1,
        "a byte-order mark is not part of the first column's name"
    );
}
