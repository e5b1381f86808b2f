//! The stroke font: letters and digits as continuous paths of unit moves on a grid 2 wide and
//! 4 high, and the plan that draws a text glyph after glyph.

use std::collections::BTreeMap;

use oddball_arm::Command;
use serde::{Deserialize, Serialize};

use crate::SessionError;

/// The stroke font: each glyph a continuous path of unit moves from its bottom-left corner on
/// a grid 2 wide and 4 high (`u`, `d`, `l`, `r`).
fn glyph(c: char) -> Option<&'static str> {
    Some(match c.to_ascii_uppercase() {
        'A' => "uuuurrddllrrdd",
        'B' => "uuuurddrddllrr",
        'C' => "uuuurrlldddd rr",
        'D' => "uuuurdrddldlrr",
        'E' => "uuuurrllddrrllddrr",
        'F' => "uuuurrllddrrlldd",
        'G' => "uuuurrllddddrruulrdd",
        'H' => "uuuuddrruudddd",
        'I' => "rrluuuulrrlddddr",
        'J' => "rruuuuddddllud",
        'K' => "uuuuddruuddrdd",
        'L' => "uuuudddd rr",
        'M' => "uuuurdduurdddd",
        'N' => "uuuurdddruuudddd",
        'O' => "uuuurrddddll rr",
        'P' => "uuuurrddlldd",
        'Q' => "uuuurrddddllrrlurd",
        'R' => "uuuurrddllrdrd",
        'S' => "rruulluurrllddrrdd",
        'T' => "ruuuulrrldddd",
        'U' => "uuuudddd rruuuudddd",
        'V' => "uuuudddrdruuuudddd",
        'W' => "uuuuddddruuddruuuudddd",
        'X' => "ruuuuddlrrlddr",
        'Y' => "ruuluuddrruuddlddr",
        'Z' => "rrlluurruullrrddllddrr",
        '0' => "uuuurrddddll rr",
        '1' => "ruuuudddd r",
        '2' => "uurruullrrddllddrr",
        '3' => "rruulruullrrdddd",
        '4' => "rruuuuddlluuddrrdd",
        '5' => "rruulluurrllddrrdd",
        '6' => "uuuurrllddrrddllrr",
        '7' => "rruuuullrrdddd",
        '8' => "uuuurrddllrrddllrr",
        '9' => "rruuuullddrrdd",
        ' ' => "rr",
        _ => return None,
    })
}

/// A planned move: the command and whether it is travel between glyphs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlannedMove {
    pub command: Command,
    pub travel: bool,
}

/// The moves that draw `text`, glyph after glyph, each glyph starting one step right of the
/// previous glyph's box on the baseline.
pub fn stroke_plan(text: &str) -> Result<Vec<PlannedMove>, SessionError> {
    let mut plan = Vec::new();
    let mut x_box = 0i64; // left edge of the current glyph box, in steps
    let (mut x, mut z) = (0i64, 0i64);
    for (k, c) in text.chars().enumerate() {
        let g = glyph(c).ok_or_else(|| SessionError::InvalidParameter {
            name: "text",
            value: text.to_string(),
            reason: format!("no glyph for {c:?}: the font has A–Z, 0–9 and space"),
        })?;
        if k > 0 {
            // Travel: down to the baseline, right (or left) to the glyph's start.
            for _ in 0..z {
                plan.push(PlannedMove {
                    command: Command::Down,
                    travel: true,
                });
            }
            z = 0;
            let dx = x_box - x;
            let cmd = if dx >= 0 {
                Command::Right
            } else {
                Command::Left
            };
            for _ in 0..dx.abs() {
                plan.push(PlannedMove {
                    command: cmd,
                    travel: true,
                });
            }
            x = x_box;
        }
        for ch in g.chars().filter(|c| !c.is_whitespace()) {
            let command = match ch {
                'u' => Command::Up,
                'd' => Command::Down,
                'l' => Command::Left,
                'r' => Command::Right,
                _ => unreachable!("glyph strings hold u, d, l, r"),
            };
            let v = command.direction();
            x += v[0] as i64;
            z += v[1] as i64;
            plan.push(PlannedMove {
                command,
                travel: false,
            });
        }
        x_box += 3;
    }
    Ok(plan)
}

/// The commands that draw `text` from its first glyph's bottom-left corner: [`stroke_plan`]'s
/// moves, travel between glyphs included (`text_commands("G")` is `oddball demo`'s letter G).
pub fn text_commands(text: &str) -> Result<Vec<Command>, SessionError> {
    Ok(stroke_plan(text)?.iter().map(|m| m.command).collect())
}

/// A glyph's box `(x_min, x_max, z_min, z_max)` and end point `(x, z)`, in steps.
pub type GlyphExtent = ((i64, i64, i64, i64), (i64, i64));

/// Extent and end point of every glyph's path.
pub fn glyph_extents() -> BTreeMap<char, GlyphExtent> {
    let chars = ('A'..='Z').chain('0'..='9').chain(std::iter::once(' '));
    chars
        .map(|c| {
            let (mut x, mut z, mut x0, mut x1, mut z0, mut z1) = (0i64, 0i64, 0, 0, 0, 0);
            for ch in glyph(c).expect("in the font").chars() {
                match ch {
                    'u' => z += 1,
                    'd' => z -= 1,
                    'l' => x -= 1,
                    'r' => x += 1,
                    _ => {}
                }
                x0 = x0.min(x);
                x1 = x1.max(x);
                z0 = z0.min(z);
                z1 = z1.max(z);
            }
            (c, ((x0, x1, z0, z1), (x, z)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_glyph_stays_in_its_box() {
        for (c, ((x0, x1, z0, z1), (x, z))) in glyph_extents() {
            assert!(
                x0 >= 0 && x1 <= 2 && z0 >= 0 && z1 <= 4,
                "{c:?}: x {x0}..{x1} z {z0}..{z1}"
            );
            assert_eq!(z, 0, "{c:?} ends on the baseline");
            if !"FJPT".contains(c) {
                assert_eq!(x, 2, "{c:?} ends at its right edge");
            }
        }
    }

    #[test]
    fn hi_plans_h_travel_and_i() {
        let plan = stroke_plan("HI").unwrap();
        let h = glyph('H').unwrap().len();
        let i = glyph('I').unwrap().len();
        // H ends at (2, 0); I starts at (3, 0): one travel step right.
        assert_eq!(plan.len(), h + 1 + i);
        assert!(plan[h].travel && plan[h].command == Command::Right);
        assert!(plan.iter().filter(|m| m.travel).count() == 1);
        assert!(stroke_plan("H!").is_err());
    }
}
