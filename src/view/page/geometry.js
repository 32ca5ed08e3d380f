// SesiGeometry: projections and isometries of S^n, H^n and E^n for the `sesi view` page.
// Plain ES2020 script (no modules): the writer concatenates it before viewer.js into one <script>.
// Interface: the "Geometry module" of the view page (docs/view.md). Conventions as in the run's
// files: sphere |x| = R with the north pole (0,..,0,+R) (the last coordinate); hyperboloid
// <x,x>_L = -R^2 with the last coordinate time-like, origin (0,..,0,R); a Euclidean box is the
// domain [0, L_k). Models and formulas: Cannon, Floyd, Kenyon, Parry, "Hyperbolic geometry" (1997)
// (the hyperboloid, Poincare disc/ball and upper half-plane models, the maps between them);
// Ratcliffe, Foundations of Hyperbolic Manifolds, ch. 3 (Lorentz transformations, boosts) and
// ch. 4 (the conformal models, the Cayley transform); Needham, Visual Complex Analysis, ch. 3
// (stereographic projection).
var SesiGeometry = (function () {
  "use strict";

  const EPS = Number.EPSILON;

  // ---- named guards for the singular expressions -------------------------------------------

  /// sin(s t) / sin(t) for s in [0, 1] (slerp weights); t -> 0: s (1 + (1 - s^2) t^2 / 6), the
  /// next term being O(t^4) < 1e-16 below the threshold.
  function sinRatio(s, t) {
    if (Math.abs(t) < 1e-4) return s * (1 + (1 - s * s) * t * t / 6);
    return Math.sin(s * t) / Math.sin(t);
  }

  /// sinh(s d) / sinh(d) for s in [0, 1]; d -> 0: s (1 - (1 - s^2) d^2 / 6) (O(d^4) next);
  /// d large: e^{(s-1) d} (1 - e^{-2 s d}) / (1 - e^{-2 d}), which does not overflow.
  function sinhRatio(s, d) {
    if (d < 1e-4) return s * (1 - (1 - s * s) * d * d / 6);
    if (d > 20) return Math.exp((s - 1) * d) * (-Math.expm1(-2 * s * d)) / (-Math.expm1(-2 * d));
    return Math.sinh(s * d) / Math.sinh(d);
  }

  /// r + x_last for a point of norm r on the sphere (the stereographic denominator). Near the
  /// south pole (x_last -> -r) it is computed as |x_s|^2 / (r - x_last), without cancellation;
  /// 0 at the pole itself, whose image is at infinity (the caller marks it not visible).
  function stereoDenominator(xs2, xl, r) {
    if (xl >= 0) return r + xl;
    return xs2 / (r - xl);
  }

  /// (x_last - R) / R = cosh(d/R) - 1 on the hyperboloid, as |x_s|^2 / (R (x_last + R)).
  function coshMinusOne(xs2, xl, R) {
    return xs2 / (R * (xl + R));
  }

  /// cosh(rho) - 1 from ep = e^rho, accurate as rho -> 0: (ep - 1)^2 / (2 ep).
  function coshm1FromEp(ep) {
    return (ep - 1) * (ep - 1) / (2 * ep);
  }

  function finite3(p) {
    return Number.isFinite(p[0]) && Number.isFinite(p[1]) && Number.isFinite(p[2]);
  }

  // ---- small dense linear algebra (row-major Float64Array) ----------------------------------

  function eye(a) {
    const m = new Float64Array(a * a);
    for (let i = 0; i < a; ++i) m[i * a + i] = 1;
    return m;
  }
  function matMul(A, B, a) {
    const C = new Float64Array(a * a);
    for (let i = 0; i < a; ++i)
      for (let k = 0; k < a; ++k) {
        const aik = A[i * a + k];
        if (aik === 0) continue;
        for (let j = 0; j < a; ++j) C[i * a + j] += aik * B[k * a + j];
      }
    return C;
  }
  function matVec(M, x, a, out) {
    for (let i = 0; i < a; ++i) {
      let s = 0;
      for (let j = 0; j < a; ++j) s += M[i * a + j] * x[j];
      out[i] = s;
    }
    return out;
  }
  function transpose(M, a) {
    const T = new Float64Array(a * a);
    for (let i = 0; i < a; ++i)
      for (let j = 0; j < a; ++j) T[j * a + i] = M[i * a + j];
    return T;
  }
  function norm(x, from, to) {
    // Scaled sum of squares: no overflow for the far hyperbolic points (|x| ~ R e^{d/R}).
    let big = 0;
    for (let i = from; i < to; ++i) big = Math.max(big, Math.abs(x[i]));
    if (big === 0 || !Number.isFinite(big)) return big;
    let s = 0;
    for (let i = from; i < to; ++i) { const v = x[i] / big; s += v * v; }
    return big * Math.sqrt(s);
  }

  // ---- S^n: rotations -------------------------------------------------------------------------

  /// The rotation in the plane of x and the north pole N = e_last taking x/|x| to N (identity
  /// when x is on the ray of N; the half turn in the plane (e_1, N) when x is on the ray of -N).
  /// With c = x_last/|x|, s = |x_s|/|x| and e = x_s/|x_s|: R = I + (c - 1)(e e^T + N N^T)
  /// + s (N e^T - e N^T), so R e = c e + s N, R N = c N - s e, R (c N + s e) = N. Angles come from
  /// the spatial part and x_last separately, never from 1 + c (which cancels near the south pole).
  function rotationToPole(x, a) {
    const m = eye(a);
    const n = a - 1;
    const s = norm(x, 0, n), xl = x[n];
    const r = Math.hypot(s, xl);
    if (!(r > 0) || !Number.isFinite(r)) return m;
    if (s === 0) {
      if (xl < 0) { m[0] = -1; m[n * a + n] = -1; }
      return m;
    }
    const c = xl / r, sn = s / r;
    for (let i = 0; i < n; ++i) {
      const ei = x[i] / s;
      for (let j = 0; j < n; ++j) m[i * a + j] += (c - 1) * ei * (x[j] / s);
      m[n * a + i] = sn * ei;
      m[i * a + n] = -sn * ei;
    }
    m[n * a + n] = c;
    return m;
  }

  // ---- H^n: Lorentz transformations kept as K B(e, e^rho) --------------------------------------
  // An isometry is stored as a rotation K of the spatial coordinates (fixing the origin) after a
  // boost B(e, ep) that takes the point R (sinh rho e, cosh rho), ep = e^rho, to the origin
  // (Ratcliffe ch. 3: every positive Lorentz matrix is a rotation times a boost). The boost is
  // applied in light-cone coordinates A = x_t + x_e, B = x_t - x_e, A B = R^2 + |x_perp|^2, which it
  // scales to A / ep and B ep: the sums that cancel are then of the size of the result, not
  // of R cosh^2 rho, so a view centred 20 R out keeps the digits the data carry (a plain matrix
  // product would lose eps R cosh^2(20) ~ 13 R). The row-major matrix m is kept for display.

  function boostApply(e, ep, x, n, R, out) {
    if (ep === 1) {  // no boost: exact (the light-cone sums below would cost eps R near the origin)
      for (let i = 0; i <= n; ++i) out[i] = x[i];
      return out;
    }
    let xe = 0;
    for (let i = 0; i < n; ++i) xe += e[i] * x[i];
    let p2 = 0;
    for (let i = 0; i < n; ++i) { const v = x[i] - xe * e[i]; out[i] = v; p2 += v * v; }
    const xt = x[n];
    const q2 = R * R + p2;           // A B on the hyperboloid
    let A, B;
    if (xe >= 0) { A = xt + xe; B = q2 / A; } else { B = xt - xe; A = q2 / B; }
    const a2 = A / ep, b2 = B * ep;
    const ye = 0.5 * (a2 - b2), yt = 0.5 * (a2 + b2);
    for (let i = 0; i < n; ++i) out[i] += ye * e[i];
    out[n] = yt;
    return out;
  }

  function hMatrix(k, e, ep, n) {
    const a = n + 1;
    const ch1 = coshm1FromEp(ep), sh = 0.5 * (ep - 1 / ep);
    const B = eye(a);
    for (let i = 0; i < n; ++i) {
      for (let j = 0; j < n; ++j) B[i * a + j] += ch1 * e[i] * e[j];
      B[i * a + n] = -sh * e[i];
      B[n * a + i] = -sh * e[i];
    }
    B[n * a + n] = 1 + ch1;
    const K = eye(a);
    for (let i = 0; i < n; ++i)
      for (let j = 0; j < n; ++j) K[i * a + j] = k[i * n + j];
    return matMul(K, B, a);
  }

  function hIso(k, e, ep, n) {
    return { m: hMatrix(k, e, ep, n), t: null, k: k, e: e, ep: ep };
  }

  function hIdentity(n) {
    const e = new Float64Array(n);
    e[0] = 1;
    return hIso(eye(n), e, 1, n);
  }

  /// The boost parameters (e, ep) taking x to the origin: e = x_s/|x_s|, ep = (x_t + |x_s|)/R
  /// (= cosh rho + sinh rho, a sum of positive terms: no cancellation however far x is).
  function hBoostTo(x, n, R) {
    const s = norm(x, 0, n);
    const e = new Float64Array(n);
    if (!(s > 0) || !Number.isFinite(s) || !(x[n] + s > 0)) { e[0] = 1; return { e: e, ep: 1 }; }
    for (let i = 0; i < n; ++i) e[i] = x[i] / s;
    return { e: e, ep: (x[n] + s) / R };
  }

  function hApply(iso, x, n, R, out, scratch) {
    const a = n + 1;
    if (!iso.k) {
      for (let i = 0; i < a; ++i) scratch[i] = x[i];  // x and out may be the same array
      return matVec(iso.m, scratch, a, out);
    }
    const y = boostApply(iso.e, iso.ep, x, n, R, scratch);
    const k = iso.k;
    for (let i = 0; i < n; ++i) {
      let s = 0;
      for (let j = 0; j < n; ++j) s += k[i * n + j] * y[j];
      out[i] = s;
    }
    out[n] = y[n];
    return out;
  }

  /// K1 B1 K2 B2 = K1 K2 (K2^T B1 K2) B2 = K1 K2 K' B3: B3 is the boost taking
  /// p3 = B2^{-1} B1'^{-1} o to o (B1' = B(K2^T e1, ep1)), and K' = B1' B2 B3^{-1} is a rotation,
  /// read off from the images of the points R (sinh 1 e_i, cosh 1) through the three boosts
  /// (each applied stably), then re-orthonormalised (Gram-Schmidt).
  function hCompose(a, b, n, R) {
    const A = n + 1;
    if (!a.k || !b.k) return { m: matMul(a.m, b.m, A), t: null };
    const e1 = new Float64Array(n);
    for (let i = 0; i < n; ++i) {
      let s = 0;
      for (let j = 0; j < n; ++j) s += b.k[j * n + i] * a.e[j];
      e1[i] = s;
    }
    const sh1 = 0.5 * (a.ep - 1 / a.ep);
    const p1 = new Float64Array(A);
    for (let i = 0; i < n; ++i) p1[i] = R * sh1 * e1[i];
    p1[n] = R * (1 + coshm1FromEp(a.ep));
    const p3 = boostApply(b.e, 1 / b.ep, p1, n, R, new Float64Array(A));
    const b3 = hBoostTo(p3, n, R);
    const kp = new Float64Array(n * n);
    const S1 = Math.sinh(1), C1 = Math.cosh(1);
    const q = new Float64Array(A), z = new Float64Array(A), w = new Float64Array(A);
    for (let i = 0; i < n; ++i) {
      q.fill(0);
      q[i] = R * S1;
      q[n] = R * C1;
      boostApply(b3.e, 1 / b3.ep, q, n, R, z);
      boostApply(b.e, b.ep, z, n, R, w);
      boostApply(e1, a.ep, w, n, R, z);
      for (let j = 0; j < n; ++j) kp[j * n + i] = z[j] / (R * S1);
    }
    orthonormaliseColumns(kp, n);
    const k = matMul(matMul(a.k, b.k, n), kp, n);
    return hIso(k, b3.e, b3.ep, n);
  }

  function orthonormaliseColumns(M, n) {
    for (let c = 0; c < n; ++c) {
      for (let p = 0; p < c; ++p) {
        let d = 0;
        for (let i = 0; i < n; ++i) d += M[i * n + c] * M[i * n + p];
        for (let i = 0; i < n; ++i) M[i * n + c] -= d * M[i * n + p];
      }
      let s = 0;
      for (let i = 0; i < n; ++i) s += M[i * n + c] * M[i * n + c];
      s = Math.sqrt(s);
      if (s > 0) for (let i = 0; i < n; ++i) M[i * n + c] /= s;
    }
  }

  /// The boost taking the origin to the point whose disc image is u (|u| < 1): direction u/|u|,
  /// rapidity 2 atanh|u|, i.e. ep = (1 + |u|)/(1 - |u|) (|u| = tanh(rho/2)); as a "boost to the
  /// origin" it is B(-u/|u|, ep). |u| is kept below 0.999 (the circle at infinity is not reachable).
  function hBoostFromDisc(u, n) {
    let r = 0;
    for (let i = 0; i < u.length; ++i) r += u[i] * u[i];
    r = Math.sqrt(r);
    if (!(r > 0) || !Number.isFinite(r)) return hIdentity(n);
    const rc = Math.min(r, 0.999);
    const e = new Float64Array(n);
    for (let i = 0; i < u.length && i < n; ++i) e[i] = -u[i] / r;
    return hIso(eye(n), e, (1 + rc) / (1 - rc), n);
  }

  // ---- labels, projection lists ---------------------------------------------------------------

  function spaceLabel(space) {
    const letter = space.kind === "sphere" ? "S" : space.kind === "hyperbolic" ? "H" : "E";
    return letter + "^" + space.dim;
  }

  function projections(space) {
    const n = space.dim;
    if (space.kind === "sphere") {
      if (n === 1) return ["circle"];
      if (n === 2) return ["sphere", "stereographic"];
      return ["stereographic"];
    }
    if (space.kind === "hyperbolic") {
      if (n === 1) return ["disc", "hyperboloid"];
      if (n === 2) return ["disc", "halfplane", "hyperboloid"];
      return ["ball"];
    }
    return ["flat"];
  }

  const LABELS = {
    circle: "Circle", sphere: "Globe", stereographic: "Stereographic projection",
    disc: "Poincare disc", halfplane: "Upper half-plane", hyperboloid: "Hyperboloid",
    ball: "Poincare ball", flat: "Flat",
  };

  function circle3(rx, plane, segs) {
    // A circle of radius rx in the coordinate plane (i, j) of R^3, as a closed polyline.
    const pts = [];
    for (let s = 0; s <= segs; ++s) {
      const phi = 2 * Math.PI * s / segs;
      const p = [0, 0, 0];
      p[plane[0]] = rx * Math.cos(phi);
      p[plane[1]] = rx * Math.sin(phi);
      pts.push(p[0], p[1], p[2]);
    }
    return pts;
  }

  // ---- the view -------------------------------------------------------------------------------

  /// axes (optional, n > 3): the 0-based coordinates shown, 3 distinct of 0..n-1 (default 0, 1, 2).
  function makeView(space, name, axes) {
    if (!space || (space.kind !== "sphere" && space.kind !== "hyperbolic" && space.kind !== "euclidean"))
      throw new Error("SesiGeometry.makeView: unknown space kind " + JSON.stringify(space && space.kind));
    const n = space.dim | 0;
    if (!(n >= 1)) throw new Error("SesiGeometry.makeView: bad dimension " + JSON.stringify(space.dim));
    const kind = space.kind;
    const R = space.radius > 0 ? space.radius : 1;
    const box = kind === "euclidean" && Array.isArray(space.box) && space.box.length === n ? space.box : null;
    const a = kind === "euclidean" ? n : n + 1;
    const names = projections(space);
    if (name === undefined || name === null || name === "") name = names[0];
    if (names.indexOf(name) < 0)
      throw new Error("SesiGeometry.makeView: projection '" + name + "' is not one of " + names.join(", ") +
                      " for " + spaceLabel(space));
    const shown = Math.min(n, 3);
    // Which coordinates of x_(1..n) (or of u) are shown when n > 3: three distinct axes.
    let ax = [0, 1, 2];
    if (n > 3 && axes !== undefined && axes !== null) {
      const ok = Array.isArray(axes) && axes.length === 3 && axes.every((k) => Number.isInteger(k) && k >= 0 && k < n) &&
        new Set(axes).size === 3;
      if (!ok) throw new Error("SesiGeometry.makeView: axes must be 3 distinct coordinates of 1.." + n);
      ax = axes.slice();
    }
    let dims;
    if (name === "sphere" || name === "ball") dims = 3;
    else if (name === "stereographic") dims = n === 2 ? 2 : 3;
    else if (name === "hyperboloid") dims = n === 1 ? 2 : 3;
    else if (name === "flat") dims = n <= 2 ? 2 : 3;
    else dims = 2;
    let note = "";
    if (n > 3) {
      note = ax[0] === 0 && ax[1] === 1 && ax[2] === 2 ? "first 3 of " + n + " coordinates"
        : "coordinates " + ax.map((k) => k + 1).join(", ") + " of " + n;
    }
    let fitted = 0;  // extent fitted to data (unbounded views), 0 until fit()

    const tmp = new Float64Array(a), tmp2 = new Float64Array(a), scratch = new Float64Array(a);
    const centre = name === "halfplane" ? [0, 1, 0] : [0, 0, 0];

    // -- isometries
    function identity() {
      if (kind === "hyperbolic") return hIdentity(n);
      return { m: eye(a), t: kind === "euclidean" ? new Float64Array(a) : null };
    }
    function centreOn(x) {
      if (kind === "sphere") return { m: rotationToPole(x, a), t: null };
      if (kind === "hyperbolic") { const b = hBoostTo(x, n, R); return hIso(eye(n), b.e, b.ep, n); }
      const t = new Float64Array(a);
      for (let i = 0; i < a; ++i) t[i] = (box ? box[i] / 2 : 0) - x[i];
      return { m: eye(a), t: t };
    }
    function compose(A, B) {
      if (kind === "hyperbolic") return hCompose(A, B, n, R);
      const m = matMul(A.m, B.m, a);
      if (kind === "sphere") return { m: m, t: null };
      const t = new Float64Array(a);
      matVec(A.m, B.t || new Float64Array(a), a, t);
      if (A.t) for (let i = 0; i < a; ++i) t[i] += A.t[i];
      return { m: m, t: t };
    }
    function apply(iso, x, out) {
      if (kind === "hyperbolic") return hApply(iso, x, n, R, out, scratch);
      for (let i = 0; i < a; ++i) scratch[i] = x[i];  // x and out may be the same array
      matVec(iso.m, scratch, a, out);
      if (kind === "euclidean") {
        if (iso.t) for (let i = 0; i < a; ++i) out[i] += iso.t[i];
        if (box) for (let i = 0; i < a; ++i) {
          const L = box[i];
          let v = out[i] - L * Math.floor(out[i] / L);
          if (v >= L) v = 0;  // -tiny - L floor(-tiny/L) rounds to L
          out[i] = v;
        }
      }
      return out;
    }
    function drag(iso, du, dv) {
      if (!(Number.isFinite(du) && Number.isFinite(dv)) || dims === 3) return iso;
      if (kind === "euclidean") {
        const t = new Float64Array(a);
        t[0] = du;
        if (a > 1) t[1] = dv;
        return compose({ m: eye(a), t: t }, iso);
      }
      if (kind === "sphere") {
        const p = new Float64Array(a);
        if (name === "circle") {
          // the top of the circle (the north pole) moves along it by the arc du
          p[0] = R * Math.sin(du); p[1] = R * Math.cos(du);
        } else {
          // inverse stereographic image of (du, dv)
          const u2 = du * du + dv * dv;
          p[0] = 2 * R * du / (1 + u2); p[1] = 2 * R * dv / (1 + u2); p[2] = R * (1 - u2) / (1 + u2);
        }
        return compose({ m: transpose(rotationToPole(p, a), a), t: null }, iso);
      }
      let u;
      if (name === "halfplane") {
        // The affine isometry w -> a w + b (a = 1 + dv, kept >= 0.05; b = du) of the half-plane,
        // which moves i to i + (du, dv) (horizontal drags are then exactly undone by the opposite
        // drag), as a disc map g = C^{-1} f C: g(0) = z1 = (w1 - i)/(w1 + i) for w1 = b + i a,
        // g'(0) = -4a/(w1 + i)^2, so g = (boost from 0 to z1) after the rotation by
        // phi = pi - 2 arg(w1 + i) (Ratcliffe ch. 4; Beardon, The Geometry of Discrete Groups, ch. 7).
        const wa = du, wb = Math.max(1 + dv, 0.05);
        const D = wa * wa + (wb + 1) * (wb + 1);
        u = [(wa * wa + wb * wb - 1) / D, -2 * wa / D];
        const phi = Math.PI - 2 * Math.atan2(wb + 1, wa);
        const k = new Float64Array([Math.cos(phi), -Math.sin(phi), Math.sin(phi), Math.cos(phi)]);
        const rot = hIso(k, new Float64Array([1, 0]), 1, 2);
        return compose(compose(hBoostFromDisc(u, n), rot), iso);
      } else if (name === "disc") {
        u = n === 1 ? [du] : [du, dv];
      } else {
        return iso;  // hyperboloid of H^1: no drag
      }
      return compose(hBoostFromDisc(u, n), iso);
    }

    // -- projection of one (already moved) point y into p[0..2]; false when it has no image
    function mapPoint(y, p) {
      p[0] = 0; p[1] = 0; p[2] = 0;
      if (kind === "sphere") {
        if (name === "circle" || name === "sphere") {
          for (let i = 0; i < shown + 1 && i < 3; ++i) p[i] = y[i] / R;
          return finite3(p);
        }
        const xs = norm(y, 0, n);
        const r = Math.hypot(xs, y[n]);
        const den = stereoDenominator(xs * xs, y[n], r);
        if (!(den > 0)) return false;
        for (let i = 0; i < shown; ++i) p[i] = y[ax[i]] / den;
        if (!finite3(p)) return false;
        // |u| over all n coordinates against 1.5 extent (2.2): the far side near the south pole
        return xs / den <= 1.5 * extentValue();
      }
      if (kind === "hyperbolic") {
        const den = R + y[n];
        if (!(den > 0)) return false;
        if (name === "disc" || name === "ball") {
          for (let i = 0; i < shown; ++i) p[i] = y[ax[i]] / den;
          return finite3(p);
        }
        if (name === "hyperboloid") {
          let xs2 = 0;
          for (let i = 0; i < n; ++i) xs2 += y[i] * y[i];
          for (let i = 0; i < n; ++i) p[i] = y[i] / R;
          p[n] = coshMinusOne(xs2, y[n], R);
          return finite3(p);
        }
        // halfplane, w = i (1 + u)/(1 - u) with u = y_s/(R + y_t), written with
        // 1 - |u|^2 = 2R/(R + y_t) and (1 - u_1)(R + y_t) = m0 computed without cancellation:
        // w = (-2 y_2 den, 2 R den) / (m0^2 + y_2^2) (y_1, y_2 the spatial coordinates).
        const y0 = y[0], y1 = y[1], yt = y[2];
        const m0 = y0 > 0 ? R + (R * R + y1 * y1) / (yt + y0) : R + yt - y0;
        const D = m0 * m0 + y1 * y1;
        p[0] = -2 * y1 * den / D;
        p[1] = 2 * R * den / D;
        if (!finite3(p)) return false;
        // a wide window shows far along the real axis: cut at 4 extents (points there are tiny)
        const ext = 4 * extentValue();
        return Math.abs(p[0]) <= ext && p[1] <= 1 + ext;
      }
      for (let i = 0; i < shown; ++i) p[i] = y[ax[i]] - (box ? box[ax[i]] / 2 : 0);
      return finite3(p);
    }

    function project(X, count, iso, out, visible) {
      const p = [0, 0, 0];
      for (let b = 0; b < count; ++b) {
        for (let i = 0; i < a; ++i) tmp[i] = X[b * a + i];
        apply(iso, tmp, tmp2);
        const ok = mapPoint(tmp2, p);
        out[3 * b] = ok ? p[0] : 0;
        out[3 * b + 1] = ok ? p[1] : 0;
        out[3 * b + 2] = ok ? p[2] : 0;
        visible[b] = ok ? 1 : 0;
      }
    }
    function projectPoint(x, iso) {
      const y = new Float64Array(a);
      apply(iso || identity(), Float64Array.from(x), y);
      const p = [0, 0, 0];
      return mapPoint(y, p) ? p : null;
    }

    function localScale(p) {
      let u2 = 0;
      for (let i = 0; i < 3; ++i) u2 += p[i] * p[i];
      switch (name) {
        case "disc": case "ball": return (1 - u2) / (2 * R);   // ds = 2R|du|/(1-|u|^2)
        case "stereographic": return (1 + u2) / (2 * R);     // ds = 2R|du|/(1+|u|^2)
        case "halfplane": return p[1] / R;                   // ds = R|dw|/Im w
        case "flat": return 1;
        default: return 1 / R;                               // circle, globe, hyperboloid (at its top)
      }
    }

    function extentValue() {
      switch (name) {
        case "disc": case "ball": case "circle": case "sphere": return 1;
        case "stereographic": return 2.2;
        case "halfplane": return 2;
        case "hyperboloid": return fitted > 0 ? fitted : 3;
        default: {
          if (box) {
            let m = 0;
            for (let i = 0; i < shown; ++i) m = Math.max(m, box[ax[i]] / 2);
            return m;
          }
          return fitted > 0 ? fitted : 1;
        }
      }
    }

    /// Unbounded views (flat without a box, hyperboloid): fit the extent to the points' images
    /// (flat: the largest |coordinate| times 1.05; hyperboloid, whose height grows as e^(d/R):
    /// the 95th percentile, so that a few far bodies do not shrink the rest to a dot); other
    /// views keep theirs. Returns extent().
    function fit(X, count, iso) {
      if (!(name === "hyperboloid" || (name === "flat" && !box))) return extentValue();
      const p = [0, 0, 0];
      const sizes = [];
      for (let b = 0; b < count; ++b) {
        for (let i = 0; i < a; ++i) tmp[i] = X[b * a + i];
        apply(iso || identity(), tmp, tmp2);
        if (!mapPoint(tmp2, p)) continue;
        sizes.push(Math.max(Math.abs(p[0] - centre[0]), Math.abs(p[1] - centre[1]), Math.abs(p[2])));
      }
      sizes.sort((u, v) => u - v);
      const m = sizes.length === 0 ? 0
        : name === "hyperboloid" ? sizes[Math.min(sizes.length - 1, Math.floor(0.95 * sizes.length))]
        : sizes[sizes.length - 1];
      fitted = m > 0 ? 1.05 * m : 0;
      return extentValue();
    }

    function outlines(iso) {
      const segs = 96;
      switch (name) {
        case "disc":
          if (n === 1) return [[-1, 0, 0, 1, 0, 0]];
          return [circle3(1, [0, 1], segs)];
        case "ball":
          return [circle3(1, [0, 1], segs), circle3(1, [0, 2], segs), circle3(1, [1, 2], segs)];
        case "circle":
          return [circle3(1, [0, 1], segs)];
        case "stereographic":
          if (n === 2) return [circle3(1, [0, 1], segs)];   // the equator, |u| = 1
          return [circle3(1, [0, 1], segs), circle3(1, [0, 2], segs), circle3(1, [1, 2], segs)];
        case "halfplane": {
          const X = 50 * extentValue();
          return [[-X, 0, 0, X, 0, 0]];
        }
        case "sphere": {
          // the equator and a meridian of the data's sphere, moved with the view
          const lines = [];
          const m = iso || identity();
          for (const plane of [[0, 1], [0, 2]]) {
            const pts = [], x = new Float64Array(3), y = new Float64Array(3);
            for (let s = 0; s <= segs; ++s) {
              const phi = 2 * Math.PI * s / segs;
              x.fill(0);
              x[plane[0]] = R * Math.cos(phi);
              x[plane[1]] = R * Math.sin(phi);
              apply(m, x, y);
              pts.push(y[0] / R, y[1] / R, y[2] / R);
            }
            lines.push(pts);
          }
          return lines;
        }
        case "hyperboloid": {
          // the hyperbolas through the top (x_1, x_2 axes), and the circles at distances T/2 and T,
          // T the distance where the surface leaves the view (sinh T = the extent)
          const lines = [];
          const T = Math.max(1, Math.asinh(extentValue()));
          for (let ax = 0; ax < n; ++ax) {
            const pts = [];
            for (let s = 0; s <= segs; ++s) {
              const t = -T + 2 * T * s / segs;
              const p = [0, 0, 0];
              p[ax] = Math.sinh(t);
              p[n] = Math.cosh(t) - 1;
              pts.push(p[0], p[1], p[2]);
            }
            lines.push(pts);
          }
          if (n === 2) {
            for (const d of [T / 2, T]) {
              const c = circle3(Math.sinh(d), [0, 1], segs);
              for (let i = 2; i < c.length; i += 3) c[i] = Math.cosh(d) - 1;
              lines.push(c);
            }
          }
          return lines;
        }
        default: {  // flat: the box's edges
          if (!box) return [];
          const h = [0, 1, 2].map((i) => (i < shown ? box[ax[i]] / 2 : 0));
          if (dims === 2) {
            if (shown === 1) return [[-h[0], 0, 0, h[0], 0, 0]];
            return [[-h[0], -h[1], 0, h[0], -h[1], 0, h[0], h[1], 0, -h[0], h[1], 0, -h[0], -h[1], 0]];
          }
          const lines = [];
          for (let ax = 0; ax < 3; ++ax) {
            const o1 = (ax + 1) % 3, o2 = (ax + 2) % 3;
            for (const s1 of [-1, 1]) for (const s2 of [-1, 1]) {
              const p = [0, 0, 0], q = [0, 0, 0];
              p[ax] = -h[ax]; q[ax] = h[ax];
              p[o1] = q[o1] = s1 * h[o1];
              p[o2] = q[o2] = s2 * h[o2];
              lines.push([p[0], p[1], p[2], q[0], q[1], q[2]]);
            }
          }
          return lines;
        }
      }
    }

    /// Points along the geodesic from xa to xb: S^n the slerp (the angle from the chord,
    /// theta = 2 asin(|xa - xb| / 2R), accurate at small angles), H^n its analogue
    /// (sinh((1-s)d) xa + sinh(s d) xb) / sinh d with d from the Lorentz chord
    /// <xa - xb, xa - xb>_L = 4 R^2 sinh^2(d/2R) (Ratcliffe ch. 3), E^n the straight segment.
    function geodesic(xa, xb, samples) {
      const cnt = Math.max(2, samples | 0);
      const out = [];
      if (kind === "euclidean") {
        for (let k = 0; k < cnt; ++k) {
          const s = k / (cnt - 1), p = new Float64Array(a);
          for (let i = 0; i < a; ++i) p[i] = (1 - s) * xa[i] + s * xb[i];
          out.push(p);
        }
        return out;
      }
      let c2 = 0;
      for (let i = 0; i < a; ++i) {
        const d = xa[i] - xb[i];
        c2 += (kind === "hyperbolic" && i === n) ? -d * d : d * d;
      }
      const chord = Math.sqrt(Math.max(c2, 0));
      if (kind === "sphere") {
        const th = 2 * Math.asin(Math.min(1, chord / (2 * R)));
        if (Math.PI - th < 1e-7) {
          // antipodal: any great half-circle; take the one through a vector orthogonal to xa
          const m = new Float64Array(a);
          let j = 0;
          for (let i = 1; i < a; ++i) if (Math.abs(xa[i]) < Math.abs(xa[j])) j = i;
          m[j] = 1;
          let d = 0;
          for (let i = 0; i < a; ++i) d += m[i] * xa[i];
          for (let i = 0; i < a; ++i) m[i] -= d * xa[i] / (R * R);
          const mn = norm(m, 0, a);
          for (let k = 0; k < cnt; ++k) {
            const s = k / (cnt - 1), p = new Float64Array(a);
            for (let i = 0; i < a; ++i)
              p[i] = Math.cos(s * Math.PI) * xa[i] + Math.sin(s * Math.PI) * R * m[i] / mn;
            out.push(p);
          }
          return out;
        }
        for (let k = 0; k < cnt; ++k) {
          const s = k / (cnt - 1), p = new Float64Array(a);
          const wa = sinRatio(1 - s, th), wb = sinRatio(s, th);
          for (let i = 0; i < a; ++i) p[i] = wa * xa[i] + wb * xb[i];
          out.push(p);
        }
        return out;
      }
      const d = 2 * Math.asinh(chord / (2 * R));
      for (let k = 0; k < cnt; ++k) {
        const s = k / (cnt - 1), p = new Float64Array(a);
        const wa = sinhRatio(1 - s, d), wb = sinhRatio(s, d);
        for (let i = 0; i < a; ++i) p[i] = wa * xa[i] + wb * xb[i];
        out.push(p);
      }
      return out;
    }

    /// The sides of the fundamental polygon (vertices v_j, in order, hyperboloid points of
    /// radius R) as geodesics of 24 samples, then each tile's Lorentz matrix (row-major 3x3;
    /// the identity's duplicate skipped) when withTiles, then iso, projected. A polyline breaks
    /// where a sample has no visible image (half-plane near infinity).
    function polygonLines(polygon, iso, withTiles) {
      if (kind !== "hyperbolic" || n !== 2 || !polygon || !Array.isArray(polygon.vertices)) return [];
      const V = polygon.vertices;
      const nv = V.length;
      const sides = [];
      for (let j = 0; j < nv; ++j) sides.push(geodesic(V[j], V[(j + 1) % nv], 24));
      const mats = [null];
      if (withTiles && Array.isArray(polygon.tiles))
        for (const T of polygon.tiles) {
          let isId = true;
          for (let i = 0; i < 9; ++i) if (Math.abs(T[i] - (i % 4 === 0 ? 1 : 0)) > 1e-12) isId = false;
          if (!isId) mats.push(Float64Array.from(T));
        }
      const J = iso || identity();
      const lines = [];
      const t1 = new Float64Array(3), t2 = new Float64Array(3), p = [0, 0, 0];
      for (const M of mats) {
        for (const side of sides) {
          let cur = [];
          for (const x of side) {
            if (M) matVec(M, x, 3, t1); else { t1[0] = x[0]; t1[1] = x[1]; t1[2] = x[2]; }
            apply(J, t1, t2);
            if (mapPoint(t2, p)) cur.push(p[0], p[1], p[2]);
            else { if (cur.length >= 6) lines.push(cur); cur = []; }
          }
          if (cur.length >= 6) lines.push(cur);
        }
      }
      return lines;
    }

    return {
      name: name, dims: dims, label: (name === "disc" && n === 1) ? "Poincare interval" : LABELS[name],
      note: note, ambient: a, centre: centre, axes: ax.slice(0, shown),
      identity: identity, centreOn: centreOn, compose: compose, apply: apply, drag: drag,
      project: project, projectPoint: projectPoint, localScale: localScale, extent: extentValue,
      fit: fit, outlines: outlines, geodesic: geodesic, polygonLines: polygonLines,
    };
  }

  // ---- colours and data -----------------------------------------------------------------------

  // matplotlib's viridis (Smith & van der Walt, 2015, "A better default colormap for
  // matplotlib", SciPy 2015; the CC0 table of mpl-colormaps): every 8th of its 256 entries
  // (indices round(k 255/32), k = 0..32), interpolated linearly between.
  const VIRIDIS = [
    [0.267004, 0.004874, 0.329415], [0.277018, 0.050344, 0.375715], [0.282327, 0.094955, 0.417331],
    [0.282884, 0.135920, 0.453427], [0.278826, 0.175490, 0.483397], [0.270595, 0.214069, 0.507052],
    [0.258965, 0.251537, 0.524736], [0.244972, 0.287675, 0.537260], [0.229739, 0.322361, 0.545706],
    [0.214298, 0.355619, 0.551184], [0.199430, 0.387607, 0.554642], [0.185556, 0.418570, 0.556753],
    [0.172719, 0.448791, 0.557885], [0.160665, 0.478540, 0.558115], [0.149039, 0.508051, 0.557250],
    [0.137770, 0.537492, 0.554906], [0.127568, 0.566949, 0.550556], [0.121148, 0.592739, 0.544641],
    [0.120081, 0.622161, 0.534946], [0.130067, 0.651384, 0.521608], [0.153894, 0.680203, 0.504172],
    [0.191090, 0.708366, 0.482284], [0.239374, 0.735588, 0.455688], [0.296479, 0.761561, 0.424223],
    [0.360741, 0.785964, 0.387814], [0.430983, 0.808473, 0.346476], [0.506271, 0.828786, 0.300362],
    [0.585678, 0.846661, 0.249897], [0.668054, 0.861999, 0.196293], [0.751884, 0.874951, 0.143228],
    [0.835270, 0.886029, 0.102646], [0.916242, 0.896091, 0.100717], [0.993248, 0.906157, 0.143936],
  ];

  function colourmap(name, s) {
    if (name !== "viridis") throw new Error("SesiGeometry.colourmap: unknown colour map '" + name + "'");
    let v = Number.isFinite(s) ? Math.min(1, Math.max(0, s)) : 0;
    const f = v * (VIRIDIS.length - 1);
    const i = Math.min(VIRIDIS.length - 2, Math.floor(f));
    const w = f - i;
    const c0 = VIRIDIS[i], c1 = VIRIDIS[i + 1];
    return [0, 1, 2].map((k) => Math.round(255 * ((1 - w) * c0[k] + w * c1[k])));
  }

  /// Hue frac(b / phi) (the golden-ratio sequence: successive bodies far apart in hue), fixed
  /// saturation 0.65 and value 0.95, HSV to RGB (Foley, van Dam et al., Computer Graphics, 13.3.4).
  function bodyColour(b) {
    const x = b * 0.618033988749895;
    const h = (x - Math.floor(x)) * 6;
    const S = 0.65, V = 0.95;
    const i = Math.floor(h) % 6, f = h - Math.floor(h);
    const p = V * (1 - S), q = V * (1 - S * f), t = V * (1 - S * (1 - f));
    const rgb = [[V, t, p], [q, V, p], [p, V, t], [p, q, V], [t, p, V], [V, p, q]][i];
    return rgb.map((c) => Math.round(255 * c));
  }

  function decodeBase64(str) {
    const bin = atob(str);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) out[i] = bin.charCodeAt(i);
    return out;
  }

  return {
    spaceLabel: spaceLabel, projections: projections, makeView: makeView,
    decodeBase64: decodeBase64, colourmap: colourmap, bodyColour: bodyColour,
    // exposed for the tests: the named guards
    guards: { sinRatio: sinRatio, sinhRatio: sinhRatio, stereoDenominator: stereoDenominator },
  };
})();
