//! The ground-truth layers a frame can carry besides `rgb` and `depth_m`, declared once: every
//! other list (the CPU and GPU outputs, the Python binding's names, `skyfall._core.LAYERS`, the
//! Python `Frame.layers` keys) is derived from [`Layer::ALL`]; which of them a frame draws is
//! the union of its stages' [`LayerSet`]s.

/// A layer of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Layer {
    /// e^(−σ d) along the pixel's ray (the haze pass).
    Transmittance,
    /// The streaks' coverage 1 − ∏(1 − aᵢ) (the particle pass, rain).
    RainAlpha,
    /// The depth of the nearest visible streak, m; inf where none (the particle pass, rain).
    RainDepth,
    /// The flakes' coverage 1 − ∏(1 − aᵢ) (the particle pass, snow).
    SnowAlpha,
    /// The depth of snow the pixel shows, m; 0 where none (the scene stage, with a snow
    /// cover): interpolated between the cover's cells; thin snow lies in patches
    /// d / `snow::cover::look::coverage`(d) deep with 0 between them, their mean d where a pixel
    /// spans many (`snow::cover::render::drawn_depth`).
    SnowDepth,
    /// The clouds' coverage 1 − ∏(1 − αᵢ) over the sky (the cloud pass).
    CloudAlpha,
    /// The share of the sun's direct light reaching the visible surface: the boxes' shadow
    /// times the clouds' attenuation Γ (the scene stage, under a sky with a sun).
    SunTransmittance,
    /// The windshield's drops' coverage, 0–1 (the windshield stage).
    DropMask,
    /// The windshield's metaball field above its 0.5 threshold, 0 off the drops (the
    /// windshield stage).
    DropHeight,
    /// The share of the visible surface under the rain's water film, 0–1; 0 on the sky, dry
    /// and snow-covered surfaces (the wet stage).
    Wetness,
    /// 1 where the visible surface is a puddle (standing water in a level surface's low
    /// points), else 0 (the wet stage).
    PuddleMask,
}

/// A set of layers: what a stage draws ([`super::Stage::layers`]), and what a frame's stages
/// draw together (the union, [`super::Plan::layers`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct LayerSet(u16);

impl LayerSet {
    /// No layer.
    pub const EMPTY: LayerSet = LayerSet(0);

    /// The set of `layers`.
    pub const fn of(layers: &[Layer]) -> Self {
        let mut s = LayerSet::EMPTY;
        let mut i = 0;
        while i < layers.len() {
            s = s.with(layers[i]);
            i += 1;
        }
        s
    }

    /// The set with `layer` added.
    pub const fn with(self, layer: Layer) -> Self {
        LayerSet(self.0 | 1 << layer.index())
    }

    /// The set with `layer` added when `when`.
    pub const fn with_if(self, layer: Layer, when: bool) -> Self {
        if when { self.with(layer) } else { self }
    }

    /// Both sets' layers.
    pub const fn union(self, other: LayerSet) -> Self {
        LayerSet(self.0 | other.0)
    }

    /// Whether `layer` is in the set.
    pub const fn contains(self, layer: Layer) -> bool {
        self.0 & 1 << layer.index() != 0
    }

    /// Whether the two sets share a layer.
    pub const fn overlaps(self, other: LayerSet) -> bool {
        self.0 & other.0 != 0
    }

    /// Whether the set is empty.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The set's layers, in the order of [`Layer::ALL`].
    pub fn iter(self) -> impl Iterator<Item = Layer> {
        Layer::ALL.into_iter().filter(move |&l| self.contains(l))
    }
}

/// How many layers there are.
pub const LAYER_COUNT: usize = 11;

impl Layer {
    /// Every layer, in the order frames list them.
    pub const ALL: [Layer; LAYER_COUNT] = [
        Layer::Transmittance,
        Layer::RainAlpha,
        Layer::RainDepth,
        Layer::SnowAlpha,
        Layer::SnowDepth,
        Layer::CloudAlpha,
        Layer::SunTransmittance,
        Layer::DropMask,
        Layer::DropHeight,
        Layer::Wetness,
        Layer::PuddleMask,
    ];

    /// The layer's name, as users see it (`frame.layers[name]`, EXR channel names).
    pub const fn name(self) -> &'static str {
        match self {
            Layer::Transmittance => "transmittance",
            Layer::RainAlpha => "rain_alpha",
            Layer::RainDepth => "rain_depth_m",
            Layer::SnowAlpha => "snow_alpha",
            Layer::SnowDepth => "snow_depth_m",
            Layer::DropMask => "drop_mask",
            Layer::DropHeight => "drop_height",
            Layer::CloudAlpha => "cloud_alpha",
            Layer::SunTransmittance => "sun_transmittance",
            Layer::Wetness => "wetness",
            Layer::PuddleMask => "puddle_mask",
        }
    }

    /// What the layer holds, in one line.
    pub const fn meaning(self) -> &'static str {
        match self {
            Layer::Transmittance => "haze transmittance e^(-sigma d) along the pixel's view ray",
            Layer::RainAlpha => "rain streak coverage 1 - prod(1 - a_i)",
            Layer::RainDepth => "depth of the nearest visible rain streak, m (inf: none)",
            Layer::SnowAlpha => "snowflake coverage 1 - prod(1 - a_i)",
            Layer::SnowDepth => {
                "depth of snow the pixel shows, m (0: none; thin snow lies in patches d / snow.coverage(d) deep, 0 between them)"
            }
            Layer::DropMask => "coverage of the windshield's drops, 0-1",
            Layer::DropHeight => {
                "the windshield's metaball field above its 0.5 threshold (0: no drop)"
            }
            Layer::CloudAlpha => "cloud coverage 1 - prod(1 - alpha_i) along the pixel's ray",
            Layer::SunTransmittance => {
                "share of direct sunlight reaching the visible surface (boxes' and clouds' shadows)"
            }
            Layer::Wetness => "share of the visible surface under the rain's water film, 0-1",
            Layer::PuddleMask => {
                "1 where the visible surface is a puddle of standing water, else 0"
            }
        }
    }

    /// The layer's value where nothing was drawn: a frame without the layer's pass holds it
    /// everywhere (no haze: transmittance 1; no rain: coverage 0, no streak at depth inf).
    pub const fn neutral(self) -> f32 {
        match self {
            Layer::Transmittance => 1.0,
            Layer::RainAlpha => 0.0,
            Layer::RainDepth => f32::INFINITY,
            Layer::SnowAlpha => 0.0,
            Layer::SnowDepth => 0.0,
            Layer::DropMask | Layer::DropHeight => 0.0,
            Layer::CloudAlpha => 0.0,
            Layer::SunTransmittance => 1.0,
            Layer::Wetness | Layer::PuddleMask => 0.0,
        }
    }

    /// Its index in [`Layer::ALL`].
    pub const fn index(self) -> usize {
        self as usize
    }
}

/// One value per layer, by layer (a buffer where the layer is drawn, None elsewhere).
#[derive(Debug, Clone, PartialEq)]
pub struct Layers<T>(pub [Option<T>; LAYER_COUNT]);

impl<T> Default for Layers<T> {
    fn default() -> Self {
        Layers(std::array::from_fn(|_| None))
    }
}

impl<T> Layers<T> {
    /// The layer's value.
    pub fn get(&self, layer: Layer) -> Option<&T> {
        self.0[layer.index()].as_ref()
    }

    /// Takes the layer's value out.
    pub fn take(&mut self, layer: Layer) -> Option<T> {
        self.0[layer.index()].take()
    }

    /// The layer's value, mutable.
    pub fn get_mut(&mut self, layer: Layer) -> Option<&mut T> {
        self.0[layer.index()].as_mut()
    }

    /// Sets the layer's value.
    pub fn set(&mut self, layer: Layer, value: T) {
        self.0[layer.index()] = Some(value);
    }
}

impl Layers<&mut [f32]> {
    /// The same buffers, borrowed again (handed to one pass and kept for the next).
    pub fn reborrow(&mut self) -> Layers<&mut [f32]> {
        let mut out = Layers::default();
        for (slot, l) in self.0.iter_mut().zip(Layer::ALL) {
            if let Some(b) = slot {
                out.set(l, &mut **b);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_layer_is_listed_once_in_order() {
        for (i, l) in Layer::ALL.iter().enumerate() {
            assert_eq!(l.index(), i);
        }
        let mut names: Vec<_> = Layer::ALL.iter().map(|l| l.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), LAYER_COUNT);
    }

    #[test]
    fn a_layer_set_holds_exactly_its_layers() {
        for (i, &l) in Layer::ALL.iter().enumerate() {
            let one = LayerSet::of(&[l]);
            assert!(one.contains(l) && !one.is_empty());
            assert_eq!(one.iter().collect::<Vec<_>>(), vec![l]);
            for &other in &Layer::ALL[i + 1..] {
                assert!(!one.contains(other) && !one.overlaps(LayerSet::of(&[other])));
                let two = one.union(LayerSet::EMPTY.with(other));
                assert_eq!(two.iter().collect::<Vec<_>>(), vec![l, other]);
            }
        }
        assert_eq!(LayerSet::of(&Layer::ALL).iter().count(), LAYER_COUNT);
        assert_eq!(
            LayerSet::EMPTY.with_if(Layer::RainAlpha, false),
            LayerSet::EMPTY
        );
        assert!(LayerSet::EMPTY.iter().next().is_none());
    }

    #[test]
    fn neutral_values_are_what_an_empty_pass_leaves() {
        // no haze: e^(-0 d) = 1; no streak: 1 - (empty product) = 0, nearest streak at inf
        assert_eq!(Layer::Transmittance.neutral(), (-0.0f32).exp());
        assert_eq!(
            Layer::RainAlpha.neutral(),
            1.0 - std::iter::empty::<f32>().product::<f32>()
        );
        assert!(Layer::RainDepth.neutral().is_infinite() && Layer::RainDepth.neutral() > 0.0);
        assert_eq!(Layer::SnowAlpha.neutral(), Layer::RainAlpha.neutral());
    }
}
