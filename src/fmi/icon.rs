//! `model.png`, the FMU's icon (FMI 2.0 section 2.2.6): a table on rollers pushed by a
//! horizontal actuator from its reaction wall, a two-storey specimen on top. Drawn with
//! plotters' primitives so the build needs no image file.

use plotters::prelude::*;
use std::path::Path;

/// Icon edge, pixels: FMI tools scale it; 256 stays sharp on high-resolution screens.
pub const ICON_PX: u32 = 256;

/// Draw the icon into `path` (PNG).
pub fn draw_icon(path: &Path) -> Result<(), String> {
    let root = BitMapBackend::new(path, (ICON_PX, ICON_PX)).into_drawing_area();
    let e = |x: DrawingAreaErrorKind<_>| x.to_string();
    let steel = RGBColor(90, 98, 110);
    let oil = RGBColor(30, 100, 190);
    let table = RGBColor(235, 140, 30);
    let specimen = RGBColor(40, 40, 40);
    root.fill(&WHITE).map_err(e)?;
    // foundation and reaction wall
    root.draw(&Rectangle::new([(8, 212), (248, 240)], steel.filled()))
        .map_err(e)?;
    root.draw(&Rectangle::new([(8, 120), (40, 212)], steel.filled()))
        .map_err(e)?;
    // actuator: cylinder and rod
    root.draw(&Rectangle::new([(40, 168), (104, 192)], oil.filled()))
        .map_err(e)?;
    root.draw(&Rectangle::new([(104, 176), (132, 184)], steel.filled()))
        .map_err(e)?;
    // table on its rollers
    root.draw(&Rectangle::new([(132, 164), (240, 196)], table.filled()))
        .map_err(e)?;
    for x in [150, 186, 222] {
        root.draw(&Circle::new((x, 204), 8, steel.filled()))
            .map_err(e)?;
    }
    // a two-storey frame on the table
    let frame = specimen.stroke_width(6);
    for x in [156, 216] {
        root.draw(&PathElement::new(vec![(x, 164), (x, 84)], frame))
            .map_err(e)?;
    }
    for y in [124, 84] {
        root.draw(&PathElement::new(vec![(150, y), (222, y)], frame))
            .map_err(e)?;
    }
    // the motion: a double arrow above the table
    let arrow = oil.stroke_width(6);
    root.draw(&PathElement::new(vec![(80, 40), (232, 40)], arrow))
        .map_err(e)?;
    for (tip, back) in [(80, 96), (232, 216)] {
        root.draw(&PathElement::new(
            vec![(back, 24), (tip, 40), (back, 56)],
            arrow,
        ))
        .map_err(e)?;
    }
    root.present().map_err(e)
}
