/// An sRGB colour with 8 bits per channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// Pure white, the background of plots and grids.
    pub const WHITE: Rgb = Rgb(255, 255, 255);
    /// Pure black, used for axes and text.
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    /// Light grey used for grid lines.
    pub const GRID: Rgb = Rgb(222, 222, 222);

    /// The `i`-th colour of the default palette (cycles after 8).
    ///
    /// Okabe & Ito's colour-blind-safe set, reordered so the first colours are the most
    /// distinct; their yellow (invisible on white) is replaced by a slate violet, and orange
    /// comes last, since within the first six it is hard to tell from vermillion.
    pub fn palette(i: usize) -> Rgb {
        const P: [Rgb; 8] = [
            Rgb(0, 114, 178),   // blue
            Rgb(213, 94, 0),    // vermillion
            Rgb(0, 158, 115),   // bluish green
            Rgb(204, 121, 167), // reddish purple
            Rgb(86, 180, 233),  // sky blue
            Rgb(117, 112, 179), // slate violet
            Rgb(0, 0, 0),       // black
            Rgb(230, 159, 0),   // orange
        ];
        P[i % P.len()]
    }
}
