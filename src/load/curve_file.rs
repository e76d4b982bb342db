//! Mitsuba 3's curve files (the `linearcurve` shape's `filename`): text, one control point per
//! line as four numbers `x y z radius` separated by spaces or tabs; a blank line (or one of
//! spaces) ends a curve, so consecutive lines are the points of one curve. Each curve needs at
//! least two points.

use super::LoadError;
use crate::geometry::roundcurve::ControlPoint;
use crate::math::Vec3;
use std::path::Path;

/// Loads a curve file: its curves, each a list of control points (file coordinates).
pub fn load_curve_file(path: &Path) -> Result<Vec<Vec<ControlPoint>>, LoadError> {
    let text = super::limits::read_text(path)?;
    parse_curve_file(&text).map_err(|(line, message)| LoadError::Format {
        path: path.to_path_buf(),
        line: (line > 0).then_some(line),
        message,
    })
}

/// Parses a curve file's text; errors carry the 1-based line (0: the file as a whole) and say
/// what was expected, with the column.
pub fn parse_curve_file(text: &str) -> Result<Vec<Vec<ControlPoint>>, (usize, String)> {
    let mut curves: Vec<Vec<ControlPoint>> = Vec::new();
    let mut open = false;
    let mut started = 0usize;
    let close = |curves: &mut Vec<Vec<ControlPoint>>, open: &mut bool, started: usize| {
        if *open && curves.last().is_some_and(|c| c.len() < 2) {
            return Err((started, "a curve needs at least two control points (lines), and this one has one".into()));
        }
        *open = false;
        Ok(())
    };
    for (ln, line) in text.lines().enumerate() {
        let line_no = ln + 1;
        if line.trim_matches([' ', '\t', '\r']).is_empty() {
            close(&mut curves, &mut open, started)?;
            continue;
        }
        let mut values = [0.0f32; 4];
        let mut rest = line;
        for (k, value) in values.iter_mut().enumerate() {
            let skipped = rest.len() - rest.trim_start_matches([' ', '\t']).len();
            let column = line.len() - rest.len() + skipped + 1;
            rest = &rest[skipped..];
            let end = rest.find([' ', '\t', '\r']).unwrap_or(rest.len());
            let what = ["x", "y", "z", "radius"][k];
            let token = &rest[..end];
            *value = token.parse::<f32>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                let found = if token.is_empty() { "the end of the line".to_string() } else { format!("'{token}'") };
                (line_no, format!("column {column}: expected a finite number ({what}; a control point is 'x y z radius'), found {found}"))
            })?;
            rest = &rest[end..];
        }
        let trailing = rest.trim_matches([' ', '\t', '\r']);
        if !trailing.is_empty() {
            let column = line.len() - rest.trim_start_matches([' ', '\t']).len() + 1;
            return Err((
                line_no,
                format!("column {column}: expected the end of the line after 'x y z radius', found '{trailing}'"),
            ));
        }
        if !open {
            curves.push(Vec::new());
            (open, started) = (true, line_no);
        }
        let [x, y, z, r] = values;
        curves.last_mut().expect("a curve is open").push(ControlPoint { p: Vec3::new(x, y, z), r });
    }
    close(&mut curves, &mut open, started)?;
    if curves.is_empty() {
        return Err((0, "no control points: the file holds no curve".into()));
    }
    Ok(curves)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba's documented example: two curves separated by a blank line.
    #[test]
    fn reads_curves_separated_by_blank_lines() {
        let text = "-1.0 0.1 0.1 0.5\n 1.0 1.4 1.2 0.5\n\n-1.0 5.0 2.2 1\n-2.3 4.0 2.3 2\n\t4.0 1.0 2.2 5\r\n 4.0 0.0 2.3 6\n\n \n";
        let c = parse_curve_file(text).unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(c[0].len(), 2);
        assert_eq!(c[1].len(), 4);
        assert_eq!(c[1][3], ControlPoint { p: Vec3::new(4.0, 0.0, 2.3), r: 6.0 });
        assert_eq!(c[0][0].p, Vec3::new(-1.0, 0.1, 0.1));
    }

    /// Errors name the line and column and what was expected.
    #[test]
    fn errors_name_line_and_column() {
        let e = parse_curve_file("0 0 0 1\n0 0 zero 1\n").unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("column 5") && e.1.contains("'zero'") && e.1.contains("z;"), "{}", e.1);
        let e = parse_curve_file("0 0 0 1\n0 0 0\n").unwrap_err();
        assert!(e.0 == 2 && e.1.contains("radius") && e.1.contains("end of the line"), "{e:?}");
        let e = parse_curve_file("0 0 0 1\n0 0 0 1 7\n").unwrap_err();
        assert!(e.0 == 2 && e.1.contains("column 9") && e.1.contains("'7'"), "{e:?}");
        let e = parse_curve_file("0 0 0 1\n1 1 1 1\n\n2 2 2 1\n\n").unwrap_err();
        assert!(e.0 == 4 && e.1.contains("at least two"), "{e:?}");
        let e = parse_curve_file("0 0 0 1\n1 1 1 inf\n").unwrap_err();
        assert!(e.0 == 2 && e.1.contains("finite"), "{e:?}");
        assert_eq!(parse_curve_file("\n  \n").unwrap_err().0, 0);
    }
}
