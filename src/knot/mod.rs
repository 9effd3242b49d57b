//! Knot tying (Lenoir et al. 2005, §5.2): a loose overhand knot as the initial shape of
//! a clamped B-spline rod, the crossings of a rod's projection, and how tight a knot is.
//!
//! ```
//! use nalgebra::Vector3;
//! use splinerod::knot::{is_trefoil_diagram, overhand_knot, projection_crossings, tightness};
//!
//! // The paper's fixed-resolution run: 11 cubic control points, a 0.1 m knot.
//! let rod = overhand_knot(&Default::default())?.rod(0.01)?;
//! let crossings = projection_crossings(&rod, Vector3::y(), 400)?; // seen from above
//! assert!(is_trefoil_diagram(&crossings));
//! let knot = tightness(&rod, Vector3::y(), 400)?.expect("knotted");
//! assert!(knot.knot_length < rod.material().rest_length);
//! # Ok::<(), splinerod::Error>(())
//! ```
//!
//! # The overhand knot ([`overhand_knot`])
//!
//! In knot units the target curve starts from the trefoil
//! \\[ T(t) = (a, b, h) = (\sin t + 2\sin 2t,\; \cos t - 2\cos 2t,\; -H \sin 3t), \\]
//! whose projection on the `(a, b)` plane has three crossings at radius 1.5 and three
//! lobes reaching radius 3, the strands at a crossing being at heights \\(\pm 0.73 H\\)
//! (`H` = 1.25). The bottom lobe, tip \\(T(\pi) = (0, -3)\\), is opened: the arc
//! \\(|t - \pi| < t_c\\) is removed, where its strands are vertical (\\(da/dt = 0\\),
//! \\(\cos(\pi - t_c) = (-1-\sqrt{129})/16\\), \\(t_c \approx 0.689\\)), just below the two
//! crossings that bound the lobe. Each cut end continues into a quarter circle of radius
//! 2 turning it outwards into a straight tail along `±a`, its height easing to 0 (cubic
//! Hermite matching the cut's height and slope). The curve runs from the `−a` tail through
//! the trefoil (`t` from \\(3\pi - t_c\\) down to \\(\pi + t_c\\)) to the `+a` tail, so it
//! keeps the trefoil's three crossings, alternating over and under. World coordinates are
//! \\((x, y, z) = k\,(a,\ h,\ b_\text{tail} - b)\\), \\(k = \text{size}/6\\) (`size` is the
//! outer diameter of the knot's projection): the knot lies flat, perpendicular to gravity
//! `−y`, three crossings are seen from above (`+y`), and the ends are `(±span/2, 0, 0)`.
//!
//! That target `P(σ)`, `σ` its arclength in `[0, Λ]`, is first fitted by least squares on
//! `m` uniform parameters (\\(C(s_j) \approx P(\sigma_j)\\), clamped uniform knots on
//! `[0, Λ]`, ends interpolated). With few control points such a fit cuts corners: it is
//! slower than 1 there and brings strands together. So it is then relaxed by
//! Levenberg–Marquardt on
//! \\[ E(q) = \int (|C'|^2 - 1)^2 ds
//!     + \mu \int \frac{|C(s) - P(\sigma(s))|^2}{\text{size}^2} ds
//!     + \frac{\kappa}{\text{size}} \iint_{|s - s'| > \ell}
//!       \Big(1 - \frac{|C(s) - C(s')|}{D}\Big)_+^2 ds\, ds' \\]
//!
//! (unit speed; near the target, \\(\sigma(s)\\) being the closest target point, updated
//! every iteration so the curve may slide along it; strands at least `D` apart), with
//! `μ = 0.3`, `κ = 30`, `D = 0.35 size`, `ℓ = 0.9 size`. Finally the knots are scaled to
//! `[0, L]`, `L` the B-spline's own arclength, so the mean of \\(|C'(s)|\\) is exactly 1,
//! and the curve is checked to be knotted (a trefoil diagram seen along `+y`, see
//! [`is_trefoil_diagram`]).
//!
//! # Crossings ([`projection_crossings`])
//!
//! The rod is sampled as a polyline of `samples` points uniform in `s` and projected on
//! the plane normal to the unit direction `d`. Every pair of non-adjacent segments that
//! meet in projection is a [`Crossing`]; the strand with the larger coordinate along
//! `d` is over (the viewer sits at \\(+\infty\, d\\)). The crossing's sign is
//! \\(\operatorname{sign}((t_\text{over} \times t_\text{under}) \cdot d)\\), `+1` for a
//! right-handed crossing; it does not depend on the side the rod is seen from. All
//! pairs are tested, O(samples²): fine for a few hundred samples. These are the crossings
//! of the sampled polyline: the samples must be finer than the rod's sharpest bends
//! (chords across a near-corner of a degree-1 rod can cross each other).
//!
//! # Tightness ([`tightness`])
//!
//! The knot's extent is the material interval \\([s_\min, s_\max]\\) holding every
//! crossing coordinate; its length is the rest arclength inside the knot. As an overhand
//! knot tightens its loop contracts and the strands wrap closer round each other, so less
//! material lies between the first and the last crossing: the excess slides out through
//! the crossings into the tails, and the knot length decreases, as does the radius of the
//! ball holding the knot section.

mod diagram;
mod relax;
mod shape;
pub mod writhe;

pub use diagram::{
    is_alternating, is_trefoil_diagram, knot_determinant, knot_diagram, knot_extent,
    projection_crossings, tightness, Crossing, KnotDiagram, Tightness,
};
pub use shape::{
    overhand_knot, overhand_knot_cancellable, OverhandKnot, OverhandSpec, MAX_CONTROL_POINTS,
};
