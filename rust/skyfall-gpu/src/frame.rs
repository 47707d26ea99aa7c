//! The GPU frame: passes chained on the device, one readback per output.

use crate::cloud::CloudPass;
use crate::context::{AdapterChoice, GpuContext, GpuError};
use crate::glow::GlowPass;
use crate::haze::HazePass;
use crate::pass::{FrameEncoder, FramePass, FrameTargets};
use crate::pool::BufferPool;
use crate::pool::Pooled;
use crate::rain::RainPass;
use crate::rain_far::FarPass;
use crate::scene_raycast::SceneRaycastPass;
use crate::wet::WetPass;
use crate::windshield::WindshieldPass;
use skyfall_core::frame::layers::{Layer, Layers};
use skyfall_core::frame::passes::Particles;
use skyfall_core::frame::stages::Frame;
use skyfall_core::frame::{
    FrameBuffers, FrameOut, RainReport, SceneRef, check_frame_size, check_photo,
};
use skyfall_core::particles::streak::PARTICLE_LAYERS;
use skyfall_core::snow::streaks::SnowStats;
use skyfall_core::stage::{Kind, Output};

/// A device with every pass compiled, reused across frames.
#[derive(Debug)]
pub struct GpuRenderer {
    /// The context.
    pub ctx: GpuContext,
    raycast: SceneRaycastPass,
    haze: HazePass,
    glow: GlowPass,
    rain: RainPass,
    far: FarPass,
    cloud: CloudPass,
    windshield: WindshieldPass,
    wet: WetPass,
    pool: BufferPool,
}

impl GpuRenderer {
    /// Creates the device and compiles the passes.
    pub fn new(choice: AdapterChoice) -> Result<Self, GpuError> {
        let ctx = GpuContext::new(choice)?;
        let (raycast, haze, glow, rain, far, cloud) = ctx.scoped(|| {
            Ok((
                SceneRaycastPass::new(&ctx),
                HazePass::new(&ctx),
                GlowPass::new(&ctx),
                RainPass::new(&ctx),
                FarPass::new(&ctx),
                CloudPass::new(&ctx),
            ))
        })?;
        let windshield = WindshieldPass::new(&ctx)?;
        let wet = WetPass::new(&ctx);
        Ok(GpuRenderer {
            ctx,
            raycast,
            haze,
            glow,
            rain,
            far,
            cloud,
            windshield,
            wet,
            pool: BufferPool::default(),
        })
    }

    /// Renders `frame` into new buffers (see [`Self::draw`]).
    pub fn render_frame(&self, frame: &Frame<'_>) -> Result<FrameBuffers, GpuError> {
        FrameBuffers::filled(frame.cam, frame.layers(), |out| {
            self.draw(frame, out).map(|(rain, _)| rain)
        })
    }

    /// Draws `frame` into `out`: its stages, each recorded as its pass into one encoder, submitted once
    /// and read back in one mapped copy.
    pub fn draw(
        &self,
        frame: &Frame<'_>,
        out: FrameOut<'_>,
    ) -> Result<(Option<RainReport>, Option<SnowStats>), GpuError> {
        let (scene, cam, light) = (frame.scene, frame.cam, frame.light);
        check_frame_size(cam)?;
        let plan = frame.plan();
        plan.check(Output::Gpu)?;
        let drawn = plan.layers();
        out.check(cam, drawn)?;
        let n = cam.pixels();
        self.ctx.check_buffer(
            &format!("a {}x{} RGB frame", cam.width, cam.height),
            (3 * n * 4) as u64,
        )?;
        let ctx = &self.ctx;
        ctx.scoped(|| {
            // The stages made first (the particles on the CPU: they do not depend on the scene).
            let prepared = frame.prepare_planned(&plan, Output::Gpu)?;
            let mut f = FrameEncoder::new(ctx, &self.pool, cam);
            let mut snow_photo = None;
            let (rgb, depth) = match scene {
                SceneRef::Boxes(_) => (f.target("rgb", 3 * n), f.target("depth", n)),
                SceneRef::Photo { rgb, depth_m } => {
                    check_photo(cam, rgb, depth_m)?;
                    match light.snow {
                        // A photo's cover whitens its pixels on the CPU (the scene stage of a
                        // photo is its copy), uploaded with its layer.
                        Some(snow) => {
                            let w = cam.width as usize;
                            let mut white = rgb.to_vec();
                            let mut layer = vec![0.0f32; cam.pixels()];
                            for (y, (row, s_row)) in
                                white.chunks_mut(3 * w).zip(layer.chunks_mut(w)).enumerate()
                            {
                                let d_row = &depth_m[y * w..(y + 1) * w];
                                snow.photo_row(cam, light.ambient, y, row, d_row, Some(s_row));
                            }
                            snow_photo = Some(f.upload("snow_depth_m", &layer));
                            (f.upload("rgb", &white), f.upload("depth", depth_m))
                        }
                        None => (f.upload("rgb", rgb), f.upload("depth", depth_m)),
                    }
                }
            };
            // The layers the passes draw, one buffer each.
            let mut layers: Layers<Pooled> = Layers::default();
            for l in Layer::ALL {
                if drawn.contains(l) {
                    match (l, snow_photo.take()) {
                        (Layer::SnowDepth, Some(b)) => layers.set(l, b),
                        (_, taken) => {
                            snow_photo = taken;
                            layers.set(l, f.target(l.name(), n));
                        }
                    }
                }
            }
            let targets = FrameTargets {
                rgb: &rgb,
                depth: &depth,
                layers: &layers,
            };
            // The stages in the plan's order, each its pass (a stage the frame prepared
            // nothing for, such as glows with no light in view, records nothing).
            for d in &prepared.plan.0 {
                match d.kind {
                    // A box scene's ray cast; a photo is its upload.
                    Kind::Scene => {
                        if let SceneRef::Boxes(b) = scene {
                            self.raycast.encode(&mut f, &targets, (b, light))?;
                        }
                    }
                    // A photo's pass, or the scene pass's wet entry point, then the grain's
                    // row averaging.
                    Kind::Wet => {
                        if let Some(w) = &prepared.wet {
                            let film = w.gpu();
                            match (w.photo_gpu(), scene) {
                                (Some(photo), _) => {
                                    self.wet.encode(&mut f, &targets, (film, photo))?;
                                }
                                (None, SceneRef::Boxes(b)) => {
                                    let wet = &self.wet;
                                    let grain = self.raycast.encode_wet(
                                        &mut f,
                                        &targets,
                                        (b, light),
                                        |f, faces| wet.film(f, &targets, &film, w.shelter(), faces),
                                    )?;
                                    self.wet
                                        .denoise(&mut f, &targets, grain, film.grain_radius_px);
                                }
                                (None, _) => {}
                            }
                        }
                    }
                    Kind::Clouds => {
                        if let Some(c) = &prepared.clouds {
                            self.cloud.encode(&mut f, &targets, &c.splats)?;
                        }
                    }
                    Kind::Haze => {
                        if let Some(h) = &prepared.haze {
                            self.haze.encode(&mut f, &targets, h.haze())?;
                        }
                    }
                    Kind::Glow => {
                        if let Some(g) = &prepared.glow {
                            self.glow.encode(&mut f, &targets, &g.glow)?;
                        }
                    }
                    Kind::Particles => {
                        if let Some(p) = prepared.particles() {
                            self.particles(&mut f, &targets, p)?;
                        }
                    }
                    Kind::Windshield => {
                        if let Some(ws) = &prepared.windshield {
                            self.windshield.encode(&mut f, &targets, ws)?;
                        }
                    }
                }
            }
            // One submission, one readback of every output.
            let FrameOut {
                rgb: rgb_out,
                depth_m: depth_out,
                layers: mut layers_out,
            } = out;
            let mut outputs = vec![(rgb, rgb_out), (depth, depth_out)];
            for l in Layer::ALL {
                if let (Some(b), Some(o)) = (layers.take(l), layers_out.take(l)) {
                    outputs.push((b, o));
                }
            }
            f.read_back(outputs)?;
            Ok((prepared.rain_report(), prepared.snow_report()))
        })
    }

    /// Records the particles: the rain's far layers, then the streaks far to near, their
    /// layers' coverages into one array of planes, copied to the frame's layers after.
    fn particles(
        &self,
        f: &mut FrameEncoder<'_>,
        targets: &FrameTargets<'_>,
        p: &Particles,
    ) -> Result<(), GpuError> {
        let n = f.cam.pixels();
        let coverage = f.target("particle coverage", PARTICLE_LAYERS.len() * n);
        if let Some(far) = &p.far {
            self.far.encode(f, targets, (far, &coverage))?;
        }
        self.rain
            .encode(f, targets, (&p.streaks, p.far.is_some(), &coverage))?;
        let bytes = (n * 4) as u64;
        for (k, l) in PARTICLE_LAYERS.iter().enumerate() {
            if let Some(target) = targets.layers.get(l.coverage) {
                f.enc.copy_buffer_to_buffer(
                    &coverage.buffer,
                    k as u64 * bytes,
                    &target.buffer,
                    0,
                    bytes,
                );
            }
        }
        f.hold([coverage]);
        Ok(())
    }

    /// Bytes of device memory the renderer keeps pooled between frames.
    pub fn pooled_bytes(&self) -> u64 {
        self.pool.pooled_bytes()
    }
}
