//! Observation of every accepted segment: floor displacements u = Φq and velocities
//! u̇ = Φq̇ per building (eq. 26), story shears V_j = k_j (u_j − u_{j−1}), their sampled and
//! continuous peaks ([`super::peaks`]), the overlap audit ([`crate::overlap`]) and the
//! history ([`crate::response::ResponseTracker`]).
//!
//! The sample work is branch-free and vectorisable; only a quantity whose rate ẏ changes
//! sign over the interval just integrated (an interior extremum, about 2 % of them on the
//! paper scene), or whose rate has one sign at both ends while the cubic Hermite
//! interpolant of (y, ẏ) at the ends turns twice inside ([`peaks::turns_twice`]: a
//! minimum and a maximum, ẏ small beside its changes, as at a floor's peak under a ground
//! acceleration that nearly balances its restoring force), takes the slow path: Hermite
//! estimate ([`peaks::hermite_extremum`], [`peaks::double_turn_estimate`]), cheap filter,
//! rigorous Hermite error bound, and, if it may raise the peak, a deferred candidate
//! refined at the end of the run ([`peaks::Deferred`]). A double turn that the cubic does
//! not show is not looked for; it can exceed the larger end by at most the Hermite error
//! bound len⁴/384·max|y⁗| (the same margin the cheap filter relies on). Before the double
//! turns were flagged, held-out random seeds 8694 and 9401 reported a floor's peak 5.7e-7
//! and 3.7e-6 below the impulse method's (the sample at the interval's end, the interior
//! maximum missed); the flag costs 2.33 M instructions per paper-scene analysis (about 9 %
//! of the 26.26 M before; its necessary condition, [`peaks::may_turn_twice`], is tested for
//! every quantity and sample, the test itself only for the vectors where that passes).
//! The overlap audit flags its pairs alike (`DoubleTurn`, shared; defect 19: a pair's
//! maximum 1.05e-7 low in the modes study's GAZLI run with 13 modes per building), its
//! estimate the cubic's local maximum ([`peaks::double_turn_maximum`]): 0.57 M instructions
//! per paper-scene analysis (28.79 M → 29.36 M).
//!
//! **Energy envelope.** A building whose response cannot reach any of its peaks over the
//! interval is not observed at all. For y = Σ_n c_n q_n over the building's modes,
//! Cauchy–Schwarz with weights ω_n² gives |y| ≤ f_y √(Σ ω_n² q_n²) ≤ f_y √(2E_b), with
//! f_y = √(Σ c_n²/ω_n²) (a static flexibility) and E_b = ½Σ(q̇_n² + ω_n² q_n²); between
//! events d√(2E_b)/dt ≤ ‖Γ_b‖ |a_g| (damping only removes energy), so over an interval of
//! length len, √(2E_b(s)) ≤ R_b = √(2E_b(0)) + len ‖Γ_b‖ max(|a₀|, |a₁|). If
//! R_b < min_y peak_y/f_y, no displacement or shear of the building can reach its running
//! peak (exact or the lower bound of a pending candidate) in the interval: the sample and
//! the extremum checks are skipped, exactly (the peaks are the same). The overlap audit
//! is skipped likewise when f_y √(R_l² + R_r²) is below every pair's running maximum of
//! y = u_left − u_right (the overlap is y − gap; the tracker keeps the maximum of y), else
//! every building is observed. Not used with a history, nor with held contacts (their
//! forces are loads the bound does not include).

use super::peaks::{self, Candidate, Target};
use super::stepper::Stepper;

impl Stepper<'_> {
    /// Observes the current instant (see module docs), in vectors of the widest instruction
    /// set ([`pulp::Arch`]; exact operations only, so bit-identical on every machine).
    #[inline(always)]
    pub(super) fn observe(&mut self) {
        struct Op<'s, 'a> {
            st: &'s mut Stepper<'a>,
        }
        impl pulp::WithSimd for Op<'_, '_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, simd: S) {
                self.st.observe_with(simd)
            }
        }
        let arch = self.arch;
        arch.dispatch(Op { st: self })
    }

    #[inline(always)]
    pub(super) fn observe_with<S: pulp::Simd>(&mut self, simd: S) {
        let len = self.interval.tau_done;
        // A new sample: every building's amplitudes are stale.
        self.amp_epoch += 1;
        let mut stored: Option<usize> = None;
        let nb = self.p.modal.buildings.len();
        let (skip_overlaps, skipping) = self.envelope(simd, len);
        if len > 0.0 {
            self.diag.building_samples += nb as u64;
            self.diag.overlap_audits_skipped +=
                u64::from(skip_overlaps && !self.overlaps.is_empty());
        }
        for b in 0..nb {
            if skipping && self.skip[b] {
                self.diag.building_samples_skipped += 1;
                self.prev_valid[b] = false;
                continue;
            }
            let bm = &self.p.modal.buildings[b];
            let (nf, pf) = (bm.n_floors, bm.padded_floors());
            // The building's parts of the flat buffers (see `Stepper::u`, `Stepper::disp_max`).
            let (o, f) = (self.floors_at(b), self.floor_at(b, 0));
            let (ur, fr) = (o..o + pf + 1, f..f + pf);
            if len > 0.0 && !self.prev_valid[b] {
                // The previous sample was skipped: the rates and values at the interval
                // start, from its modal state.
                let (x0, v0) = (&self.interval.x0, &self.interval.v0);
                let (up, udp) = (&mut self.u_prev[ur.clone()], &mut self.ud_prev[ur.clone()]);
                bm.to_floors2(x0, v0, &mut up[1..], &mut udp[1..]);
            }
            // (Read only above: this sample becomes the previous one.)
            self.prev_valid[b] = true;
            let (u, ud) = (&mut self.u[ur.clone()], &mut self.ud[ur.clone()]);
            bm.to_floors2(&self.s.x, &self.s.v, &mut u[1..], &mut ud[1..]);
            let (raised, turns) = sample(
                simd,
                Sample {
                    u,
                    ud,
                    up: &self.u_prev[ur.clone()],
                    udp: &self.ud_prev[ur.clone()],
                    k: &self.stiffness[fr.clone()],
                    len,
                },
                &mut self.disp_max[fr.clone()],
                &mut self.shear_max[fr.clone()],
                &mut self.flags,
            );
            self.env_stale[b] |= raised;
            if turns && len > 0.0 {
                // The rare slow path, in the order floor 0 displacement, story 0 shear,
                // floor 1 …: each quantity whose rate changes sign (the set bits of the
                // words of `sample`, lowest first) and that passes the first filter of
                // `interior_extremum` (decided here for all of them at once: the slow path
                // of one quantity changes nothing that filter reads for another).
                let groups = pf.div_ceil(TURN_GROUP);
                for g in 0..groups {
                    let mut w = self.cubic_filter(b, pf, g, len);
                    while w != 0 {
                        let t = w.trailing_zeros() as usize;
                        w &= w - 1;
                        let i = g * TURN_GROUP + t / 2;
                        self.interior_extremum(b, i, t & 1 == 1, len, &mut stored);
                    }
                }
            }
            if self.history.is_some() {
                self.tracker.observe(b, &self.u[ur.clone()][1..=nf]);
                self.tracker.observe_velocity(b, &self.ud[ur][1..=nf]);
            }
            // The envelope threshold min_y peak_y/f_y, recomputed when a peak (or a lower
            // bound) has grown: peaks only grow, so an older threshold is a safe one.
            if !self.env_stale[b] {
                continue;
            }
            self.env_stale[b] = false;
            // Running minima in vectors over the padded floors (a padding floor's 0 · ∞ = NaN
            // is never below one), then the least of them: the minimum of the same values.
            let (inv_d, inv_s) = self.env_inv[2 * fr.start..][..2 * pf].split_at(pf);
            let (dm, dl) = (&self.disp_max[fr.clone()], &self.disp_lower[fr.clone()]);
            let (sm, sl) = (&self.shear_max[fr.clone()], &self.shear_lower[fr]);
            let (dm, dmt) = S::as_simd_f64s(dm);
            let (dl, dlt) = S::as_simd_f64s(dl);
            let (sm, smt) = S::as_simd_f64s(sm);
            let (sl, slt) = S::as_simd_f64s(sl);
            let (id, idt) = S::as_simd_f64s(inv_d);
            let (is, ist) = S::as_simd_f64s(inv_s);
            let mut mv = simd.splat_f64s(f64::INFINITY);
            let least = |a, b| simd.select_f64s(simd.less_than_f64s(b, a), b, a);
            let most = |a, b| simd.select_f64s(simd.greater_than_f64s(a, b), a, b);
            let nv = dm.len().min(dl.len()).min(sm.len()).min(sl.len());
            for i in 0..nv.min(id.len()).min(is.len()) {
                mv = least(mv, simd.mul_f64s(most(dm[i], dl[i]), id[i]));
                mv = least(mv, simd.mul_f64s(most(sm[i], sl[i]), is[i]));
            }
            let mut thr = f64::INFINITY;
            for &x in pulp::bytemuck::cast_slice::<S::f64s, f64>(std::slice::from_ref(&mv)) {
                thr = if x < thr { x } else { thr };
            }
            for i in 0..dmt.len() {
                let pd = if dmt[i] > dlt[i] { dmt[i] } else { dlt[i] } * idt[i];
                let ps = if smt[i] > slt[i] { smt[i] } else { slt[i] } * ist[i];
                thr = if pd < thr { pd } else { thr };
                thr = if ps < thr { ps } else { thr };
            }
            self.env_thr[b] = thr;
        }
        if !self.overlaps.is_empty() && !skip_overlaps {
            self.observe_overlaps(simd, len, &mut stored);
        }
        // The current sample becomes the previous one (buffers exchanged). A skipped
        // building's parts are exchanged too, stale (`prev_valid` false): its next
        // observation over an interval (len > 0) rebuilds both from the interval's start
        // before reading them; one of length 0 (an event at the interval's start) reads them
        // only for rate sign changes, which it ignores (the slow path and the overlap
        // extrema need len > 0), and its own sample becomes the previous one.
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.ud_prev, &mut self.ud);
        if self.history.is_some() {
            // Held forces are linear in time over the interval's planned length.
            let iv = &self.interval;
            let r = if iv.tau > 0.0 {
                iv.tau_done / iv.tau
            } else {
                0.0
            };
            for (now, (f0, f1)) in self
                .held_force_now
                .iter_mut()
                .zip(self.held_force_start.iter().zip(&self.held_force))
            {
                *now = f0 + (f1 - f0) * r;
            }
            self.tracker.observe_contact_forces(&self.held_force_now);
            self.tracker.sample(self.s.t, self.history.as_deref_mut());
        }
        if self.audit.is_some() {
            self.audit_interval();
        }
    }

    /// Sets `skip` per building from the energy envelope (see module docs) and returns
    /// whether the overlap audit can be skipped too, and whether `skip` holds (else every
    /// building is observed, whatever `skip` holds).
    #[inline(always)]
    fn envelope<S: pulp::Simd>(&mut self, simd: S, len: f64) -> (bool, bool) {
        if !(len > 0.0) || self.history.is_some() || self.interval.fc.is_some() {
            self.env_e2_fresh = false;
            return (false, false);
        }
        let (p, iv) = (self.p, &self.interval);
        let amax = iv.a0.abs().max(iv.a1.abs());
        let mut any = false;
        let fresh = std::mem::take(&mut self.env_e2_fresh);
        if !fresh {
            // 2E_b not given by the fast path: computed here, into the same buffer.
            for (e2, bm) in self.env_e2.iter_mut().zip(&p.modal.buildings) {
                *e2 = twice_energy(&iv.x0, &iv.v0, &p.omega2, bm.range.clone());
            }
        }
        let nb = p.modal.buildings.len();
        let (r, skip) = (&mut self.env_r[..nb], &mut self.skip[..nb]);
        let (e2, gamma, thr) = (
            &self.env_e2[..nb],
            &self.env_gamma[..nb],
            &self.env_thr[..nb],
        );
        for b in 0..nb {
            // A relative margin of 1e-9 covers the round-off of the bound itself.
            let rb = (e2[b].sqrt() + len * gamma[b] * amax) * (1.0 + 1e-9);
            r[b] = rb;
            skip[b] = rb < thr[b];
            any |= skip[b];
        }
        if self.overlaps.is_empty() {
            return (true, any);
        }
        if self.overlap_stale {
            // Per run, the smallest max(maximum, lower)/f_y of its pairs (maxima of
            // y = u_left − u_right; 0 if one is not positive): every pair of the run passes
            // the test below iff this one does.
            // (Branch-free: all positive, then the least; the same value.)
            for (run, lim) in self.overlap_runs.iter().zip(&mut self.overlap_lim) {
                let r = run.k0..run.k0 + run.n;
                let (mx, mxt) = S::as_simd_f64s(&self.overlaps.max[r.clone()]);
                let (lo, lot) = S::as_simd_f64s(&self.overlap_lower[r.clone()]);
                let (inv, invt) = S::as_simd_f64s(&self.overlap_inv[r]);
                let (zero, inf) = (simd.splat_f64s(0.0), simd.splat_f64s(f64::INFINITY));
                let (mut mv, mut bad) = (inf, simd.less_than_f64s(inf, zero));
                for ((&a, &b), &f) in mx.iter().zip(lo).zip(inv) {
                    let l = simd.mul_f64s(simd.max_f64s(a, b), f);
                    bad = simd.or_m64s(bad, simd.not_m64s(simd.greater_than_f64s(l, zero)));
                    mv = simd.select_f64s(simd.less_than_f64s(l, mv), l, mv);
                }
                let mut m = f64::INFINITY;
                let mut ok = !self::any(simd, bad);
                for &x in pulp::bytemuck::cast_slice::<S::f64s, f64>(std::slice::from_ref(&mv)) {
                    m = if x < m { x } else { m };
                }
                for ((&a, &b), &f) in mxt.iter().zip(lot).zip(invt) {
                    let l = a.max(b) * f;
                    ok &= l > 0.0;
                    m = if l < m { l } else { m };
                }
                *lim = if ok { m } else { 0.0 };
            }
            self.overlap_stale = false;
        }
        for (run, &lim) in self.overlap_runs.iter().zip(&self.overlap_lim) {
            let (rl, rr) = (self.env_r[run.left], self.env_r[run.right]);
            // √(R_l² + R_r²) < best/f_y, squared (best > 0 needed, the bound is ≥ 0).
            if !(lim > 0.0 && (rl * rl + rr * rr) * (1.0 + 1e-9) < lim * lim) {
                // A pair may reach its maximum: observe every building.
                return (false, false);
            }
        }
        (true, any)
    }

    /// Values and rates (y0, ẏ0, y1, ẏ1) of floor displacement `i` (or story shear `i` if
    /// `story`) of building `b` at the previous and the current sample: the same arithmetic
    /// as [`sample`].
    #[inline]
    fn ends(&self, b: usize, i: usize, story: bool) -> (f64, f64, f64, f64) {
        let o = self.floors_at(b);
        let (u, ud) = (&self.u[o..], &self.ud[o..]);
        let (up, udp) = (&self.u_prev[o..], &self.ud_prev[o..]);
        if story {
            let k = self.stiffness[self.floor_at(b, i)];
            (
                k * (up[i + 1] - up[i]),
                k * (udp[i + 1] - udp[i]),
                k * (u[i + 1] - u[i]),
                k * (ud[i + 1] - ud[i]),
            )
        } else {
            (up[i + 1], udp[i + 1], u[i + 1], ud[i + 1])
        }
    }

    /// The set bits of turn word `g` of building `b` (`n` padded floors; see [`sample`]) whose
    /// quantity passes the first filter of [`Stepper::interior_extremum`] (the same values,
    /// the same test).
    #[inline(never)]
    fn cubic_filter(&self, b: usize, n: usize, g: usize, len: f64) -> u64 {
        let mut w = self.flags[g].to_bits();
        let mut keep = w;
        // (Indexed in the flat buffers: only the set bits' quantities are read.)
        let (o, f) = (self.floors_at(b), self.floor_at(b, 0));
        let (u, ud, up, udp) = (&self.u, &self.ud, &self.u_prev, &self.ud_prev);
        let c = 4.0 / 27.0 * len;
        while w != 0 {
            let t = w.trailing_zeros() as usize;
            w &= w - 1;
            let i = g * TURN_GROUP + t / 2;
            debug_assert!(i < n);
            let (j, fi) = (o + i, f + i);
            let ((y0, yd0, y1, yd1), peak) = if t & 1 == 1 {
                let k = self.stiffness[fi];
                (
                    (
                        k * (up[j + 1] - up[j]),
                        k * (udp[j + 1] - udp[j]),
                        k * (u[j + 1] - u[j]),
                        k * (ud[j + 1] - ud[j]),
                    ),
                    self.shear_max[fi].max(self.shear_lower[fi]),
                )
            } else {
                (
                    (up[j + 1], udp[j + 1], u[j + 1], ud[j + 1]),
                    self.disp_max[fi].max(self.disp_lower[fi]),
                )
            };
            if cubic_bound(y0, yd0, y1, yd1, c) * (1.0 + 1e-9) < 0.9 * peak {
                keep &= !(1 << t);
            }
        }
        keep
    }

    /// The slow path of one flagged quantity of building `b` (floor displacement `i`, or
    /// story shear `i` if `story`): Hermite estimate h of the interior extremum; a cheap
    /// filter (the Hermite error is a small fraction of the content at the interval's
    /// frequencies, (ω len)⁴/384 ≤ 3e-3 for ω len ≤ 1, so an estimate below 90 % of the
    /// running peak cannot raise it); the rigorous bound |y − H| ≤ len⁴/384·Σ|c|ω⁴|A − iB|;
    /// a candidate for the end of the run if |h| + bound reaches the running peak.
    #[cold]
    fn interior_extremum(
        &mut self,
        b: usize,
        i: usize,
        story: bool,
        len: f64,
        stored: &mut Option<usize>,
    ) {
        let (y0, yd0, y1, yd1) = self.ends(b, i, story);
        let f = self.floor_at(b, i);
        let (exact, lower) = if story {
            (self.shear_max[f], self.shear_lower[f])
        } else {
            (self.disp_max[f], self.disp_lower[f])
        };
        let peak = exact.max(lower);
        // |H| ≤ max(|y0|, |y1|) + 4/27 len (|ẏ0| + |ẏ1|) (the Hermite basis functions of
        // the values are ≥ 0 and sum to 1, those of the slopes are at most 4/27 in size):
        // most flagged extrema are far below the peak and need no Hermite estimate.
        if cubic_bound(y0, yd0, y1, yd1, 4.0 / 27.0 * len) * (1.0 + 1e-9) < 0.9 * peak {
            return;
        }
        // Rates of one sign at both ends: flagged as a possible double turn (`sample`).
        let estimate = if yd0 * yd1 >= 0.0 {
            Some(peaks::double_turn_estimate(y0, yd0, y1, yd1, len))
        } else {
            peaks::hermite_extremum(y0, yd0, y1, yd1, len)
        };
        let Some((th, h)) = estimate else {
            return;
        };
        if h.abs() < 0.9 * peak {
            return;
        }
        let p = self.p;
        let bm = &p.modal.buildings[b];
        let (nmb, first, nf) = (bm.range.len(), bm.range.start, bm.n_floors);
        let coef = &mut self.coef[..nmb];
        if story {
            coef.copy_from_slice(&self.shear_rows[b][i * nmb..(i + 1) * nmb]);
        } else {
            for (m, c) in coef.iter_mut().enumerate() {
                *c = bm.phi[m * nf + i];
            }
        }
        if self.amp_valid[b] != self.amp_epoch {
            let r = bm.range.clone();
            let (arch, iv) = (self.arch, &self.interval);
            peaks::amplitudes(arch, &p.modal, &self.amp_k, r, iv, &mut self.obs_amp);
            self.amp_valid[b] = self.amp_epoch;
        }
        let bound = peaks::hermite_error_bound(&p.modal, first, coef, &self.obs_amp, len);
        if h.abs() + bound < peak {
            return;
        }
        let lb = h.abs() - bound;
        if story {
            self.shear_lower[f] = lower.max(lb);
        } else {
            self.disp_lower[f] = lower.max(lb);
        }
        self.env_stale[b] = true;
        let interval = *stored.get_or_insert_with(|| self.deferred.store(&self.interval, self.s.t));
        self.deferred.candidates.push(Candidate {
            target: if story {
                Target::Shear {
                    building: b,
                    story: i,
                }
            } else {
                Target::Displacement {
                    building: b,
                    floor: i,
                }
            },
            interval,
            s0: th * len,
            upper: h.abs() + bound,
        });
    }

    /// The overlap audit at the current sample: u_left − u_right of every audited pair at
    /// the sample and, when its rate changes sign from + to − over the interval since the
    /// previous sample (length `len`), or has one sign at both ends while its cubic Hermite
    /// interpolant turns twice inside ([`DoubleTurn`], defect 19), a candidate interior
    /// maximum, found as the story-shear and displacement peaks are (Hermite estimate,
    /// [`peaks::hermite_extremum`] or [`peaks::double_turn_maximum`], cheap filter, rigorous
    /// Hermite error bound over both buildings' modes, deferred refinement).
    #[inline(always)]
    fn observe_overlaps<S: pulp::Simd>(&mut self, simd: S, len: f64, stored: &mut Option<usize>) {
        // First pass, every pair: the sample (a running maximum, branch-free) and whether the
        // rate turns from + to − over the interval (rare: only those go on).
        let (turns, raised) = pulp::WithSimd::with_simd(OverlapPass { st: self, len }, simd);
        self.overlap_stale |= raised;
        if !(len > 0.0) || !turns {
            return;
        }
        for k in 0..self.overlaps.pairs.len() {
            if self.overlap_turn[k] != 0.0 {
                self.overlap_extremum(k, len, stored);
            }
        }
    }

    /// The rare slow path of overlap pair `k` whose rate turns from + to − over the
    /// interval of length `len`, or may turn twice inside it (see
    /// [`Stepper::observe_overlaps`]).
    #[cold]
    #[inline(never)]
    fn overlap_extremum(&mut self, k: usize, len: f64, stored: &mut Option<usize>) {
        let (u, ud, up, udp) = (&self.u, &self.ud, &self.u_prev, &self.ud_prev);
        let op = &self.overlaps.pairs[k];
        let (l, i, r, j) = (op.left, op.left_dof, op.right, op.right_dof);
        // The flat buffers' indices (past the leading zero of each building's part).
        let (i, j) = (self.floors_at(l) + i + 1, self.floors_at(r) + j + 1);
        let y1 = u[i] - u[j];
        let (y0, yd0, yd1) = (up[i] - up[j], udp[i] - udp[j], ud[i] - ud[j]);
        let best = self.overlaps.max[k].max(self.overlap_lower[k]);
        // H ≤ max(y0, y1) + 4/27 len (|ẏ0| + |ẏ1|) (see `interior_extremum`), and the
        // filter below drops h < best/1.1 (best > 0) or h < best/0.9 (best ≤ 0).
        let cubic_bound = y0.max(y1) + 4.0 / 27.0 * len * (yd0.abs() + yd1.abs());
        let bound = cubic_bound + 1e-9 * cubic_bound.abs();
        if bound + 0.1 * bound.abs() < best {
            return;
        }
        // Rates of one sign at both ends: flagged as a possible double turn (`OverlapPass`).
        let estimate = if yd0 * yd1 >= 0.0 {
            Some(peaks::double_turn_maximum(y0, yd0, y1, yd1, len))
        } else {
            peaks::hermite_extremum(y0, yd0, y1, yd1, len)
        };
        let Some((th, h)) = estimate else {
            return;
        };
        // Cheap filter, as for the peaks: the Hermite error is a small fraction of the
        // content at the interval's frequencies.
        if h + 0.1 * h.abs() < best {
            return;
        }
        let modal = &self.p.modal;
        for b in [l, r] {
            if self.amp_valid[b] != self.amp_epoch {
                let range = modal.buildings[b].range.clone();
                let (arch, iv) = (self.arch, &self.interval);
                peaks::amplitudes(arch, modal, &self.amp_k, range, iv, &mut self.obs_amp);
                self.amp_valid[b] = self.amp_epoch;
            }
        }
        let c = &self.overlap_rows[k];
        let bound = peaks::hermite_error_bound(modal, 0, c, &self.obs_amp, len);
        if h + bound < best {
            return;
        }
        self.overlap_lower[k] = self.overlap_lower[k].max(h - bound);
        self.overlap_stale = true;
        let interval = *stored.get_or_insert_with(|| self.deferred.store(&self.interval, self.s.t));
        self.deferred.candidates.push(Candidate {
            target: Target::Overlap { pair: k },
            interval,
            s0: th * len,
            upper: h + bound,
        });
    }

    /// Refines the deferred candidates (see [`peaks::Deferred`]) into the exact peaks and
    /// overlap maxima.
    pub(super) fn resolve_deferred(&mut self) {
        let p = self.p;
        let modal = &p.modal;
        let best = |st: &Self, c: &Candidate| match c.target {
            Target::Displacement { building, floor } => st.disp_max[st.floor_at(building, floor)],
            Target::Shear { building, story } => st.shear_max[st.floor_at(building, story)],
            Target::Overlap { pair } => st.overlaps.max[pair],
        };
        // Only candidates that can beat their peak now are ordered (peaks only grow, so the
        // others would be skipped below anyway; the survivors keep their relative order).
        let order = self.deferred.order_where(|c| !(c.upper < best(self, c)));
        for k in order {
            let c = self.deferred.candidates[k];
            let iv = self.deferred.interval(c.interval);
            if c.upper < best(self, &c) {
                continue;
            }
            match c.target {
                Target::Overlap { pair } => {
                    let a = peaks::arcs_of(
                        modal,
                        0..modal.len(),
                        iv.x0,
                        iv.v0,
                        iv.fc,
                        iv.a0,
                        iv.a1,
                        iv.tau,
                    );
                    let (s, y) =
                        peaks::refine_at(modal, 0, &self.overlap_rows[pair], &a, iv.len, c.s0);
                    self.overlaps.offer(pair, iv.t_end - iv.len + s, y);
                }
                Target::Displacement {
                    building: b,
                    floor: i,
                }
                | Target::Shear {
                    building: b,
                    story: i,
                } => {
                    let bm = &modal.buildings[b];
                    let (nmb, first, nf) = (bm.range.len(), bm.range.start, bm.n_floors);
                    let story = matches!(c.target, Target::Shear { .. });
                    let coef = &mut self.coef[..nmb];
                    if story {
                        coef.copy_from_slice(&self.shear_rows[b][i * nmb..(i + 1) * nmb]);
                    } else {
                        for (m, cf) in coef.iter_mut().enumerate() {
                            *cf = bm.phi[m * nf + i];
                        }
                    }
                    let a = peaks::arcs_of(
                        modal,
                        bm.range.clone(),
                        iv.x0,
                        iv.v0,
                        iv.fc,
                        iv.a0,
                        iv.a1,
                        iv.tau,
                    );
                    let y = peaks::refine(modal, first, coef, &a, iv.len, c.s0).abs();
                    let f = self.floor_at(b, i);
                    let m = if story {
                        &mut self.shear_max[f]
                    } else {
                        &mut self.disp_max[f]
                    };
                    *m = m.max(y);
                }
            }
        }
        self.deferred.candidates.clear();
    }
}

/// The first pass of the overlap audit over every pair (see [`Stepper::observe_overlaps`]),
/// in vectors of the widest instruction set: the running maxima (and their times) of
/// u_left − u_right, and whether each pair's rate turns from + to − over the interval or
/// may turn twice inside it ([`DoubleTurn`]) (`overlap_turn`: 1 or 0). Returns (some pair
/// is flagged, some maximum was raised).
struct OverlapPass<'s, 'a> {
    st: &'s mut Stepper<'a>,
    /// Length of the interval since the previous sample, s.
    len: f64,
}

impl pulp::WithSimd for OverlapPass<'_, '_> {
    type Output = (bool, bool);

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> (bool, bool) {
        let st = self.st;
        let (u, ud, up, udp) = (&st.u, &st.ud, &st.u_prev, &st.ud_prev);
        // (`Stepper::floors_at` by hand: `st` is borrowed by field below.)
        let stride = st.fs + 1;
        let now = st.s.t;
        let ov = &mut st.overlaps;
        let (zero, one, nowv) = (
            simd.splat_f64s(0.0),
            simd.splat_f64s(1.0),
            simd.splat_f64s(now),
        );
        let (mut tv, mut rv) = (
            simd.less_than_f64s(one, zero),
            simd.less_than_f64s(one, zero),
        );
        let (mut turns, mut raised) = (false, false);
        let two_turns = DoubleTurn::new(simd, self.len);
        // One vector of pairs (a macro, not a closure: closures do not inherit the
        // instruction set).
        macro_rules! pass {
            ($max:expr, $time:expr, $flag:expr, $ul:expr, $ur:expr, $vl:expr, $vr:expr, $pl:expr, $pr:expr, $ql:expr, $qr:expr) => {{
                let (max, time, flag) = ($max, $time, $flag);
                let y1 = simd.sub_f64s($ul, $ur);
                let up = simd.greater_than_f64s(y1, *max);
                *max = simd.select_f64s(up, y1, *max);
                *time = simd.select_f64s(up, nowv, *time);
                let (r0, r1) = (simd.sub_f64s($pl, $pr), simd.sub_f64s($vl, $vr));
                let turn = simd.and_m64s(
                    simd.greater_than_f64s(r0, zero),
                    simd.less_than_f64s(r1, zero),
                );
                // Or a double turn (defect 19): a maximum inside while the rate has one sign
                // at both ends (rare to pass the necessary condition).
                let y0 = simd.sub_f64s($ql, $qr);
                let may = two_turns.may(simd, y0, r0, y1, r1);
                let turn = if any(simd, may) {
                    simd.or_m64s(
                        turn,
                        simd.and_m64s(may, two_turns.test(simd, y0, r0, y1, r1)),
                    )
                } else {
                    turn
                };
                *flag = simd.select_f64s(turn, one, zero);
                tv = simd.or_m64s(tv, turn);
                rv = simd.or_m64s(rv, up);
            }};
        }
        let lanes = std::mem::size_of::<S::f64s>() / std::mem::size_of::<f64>();
        for run in &st.overlap_runs {
            let (n, k0) = (run.n, run.k0);
            // The flat buffers' indices (past the leading zero of each building's part).
            let (i0, j0) = (
                run.left * stride + run.i0 + 1,
                run.right * stride + run.j0 + 1,
            );
            let (ul, ur) = (&u[i0..i0 + n], &u[j0..j0 + n]);
            let (vl, vr) = (&ud[i0..i0 + n], &ud[j0..j0 + n]);
            let (pl, pr) = (&udp[i0..i0 + n], &udp[j0..j0 + n]);
            let (ql, qr) = (&up[i0..i0 + n], &up[j0..j0 + n]);
            let (max, mt) = S::as_mut_simd_f64s(&mut ov.max[k0..k0 + n]);
            let (time, tt) = S::as_mut_simd_f64s(&mut ov.time[k0..k0 + n]);
            let (flag, ft) = S::as_mut_simd_f64s(&mut st.overlap_turn[k0..k0 + n]);
            let (ulv, ult) = S::as_simd_f64s(ul);
            let (urv, urt) = S::as_simd_f64s(ur);
            let (vlv, vlt) = S::as_simd_f64s(vl);
            let (vrv, vrt) = S::as_simd_f64s(vr);
            let (plv, plt) = S::as_simd_f64s(pl);
            let (prv, prt) = S::as_simd_f64s(pr);
            let (qlv, qlt) = S::as_simd_f64s(ql);
            let (qrv, qrt) = S::as_simd_f64s(qr);
            for ((((((((((max, time), flag), ul), ur), vl), vr), pl), pr), ql), qr) in max
                .iter_mut()
                .zip(time.iter_mut())
                .zip(flag.iter_mut())
                .zip(ulv)
                .zip(urv)
                .zip(vlv)
                .zip(vrv)
                .zip(plv)
                .zip(prv)
                .zip(qlv)
                .zip(qrv)
            {
                pass!(max, time, flag, *ul, *ur, *vl, *vr, *pl, *pr, *ql, *qr);
            }
            if !mt.is_empty() && n >= lanes {
                // The last `lanes` pairs as one more vector, overlapping the previous one:
                // a pair seen twice is left as it was (its maximum already holds y1, the
                // same flag is written again), so this is the scalar loop below.
                let o = n - lanes;
                let v = |x: &[f64]| S::as_simd_f64s(&x[o..]).0[0];
                let (max, _) = S::as_mut_simd_f64s(&mut ov.max[k0 + o..k0 + n]);
                let (time, _) = S::as_mut_simd_f64s(&mut ov.time[k0 + o..k0 + n]);
                let (flag, _) = S::as_mut_simd_f64s(&mut st.overlap_turn[k0 + o..k0 + n]);
                let (ul, ur, vl, vr, pl, pr) = (v(ul), v(ur), v(vl), v(vr), v(pl), v(pr));
                let (ql, qr) = (v(ql), v(qr));
                pass!(
                    &mut max[0],
                    &mut time[0],
                    &mut flag[0],
                    ul,
                    ur,
                    vl,
                    vr,
                    pl,
                    pr,
                    ql,
                    qr
                );
            } else {
                for t in 0..mt.len() {
                    let y1 = ult[t] - urt[t];
                    let up = y1 > mt[t];
                    mt[t] = if up { y1 } else { mt[t] };
                    tt[t] = if up { now } else { tt[t] };
                    let (r0, r1) = (plt[t] - prt[t], vlt[t] - vrt[t]);
                    // (The vectors' decision, the same operations.)
                    let turn =
                        ((r0 > 0.0) & (r1 < 0.0)) || two_turns.scalar(qlt[t] - qrt[t], r0, y1, r1);
                    ft[t] = if turn { 1.0 } else { 0.0 };
                    turns |= turn;
                    raised |= up;
                }
            }
        }
        (turns | any(simd, tv), raised | any(simd, rv))
    }
}

/// 2E = Σ_n (q̇_n² + ω_n² q_n²) over the modes `r` (four partial sums over chunks of 4
/// modes from the range start, the tail into the first; the order does not matter for the
/// bounds that use it, whose margins cover the round-off).
#[inline(always)]
pub(super) fn twice_energy(x: &[f64], v: &[f64], w2: &[f64], r: std::ops::Range<usize>) -> f64 {
    let (x, v, w2) = (&x[r.clone()], &v[r.clone()], &w2[r]);
    let mut acc = [0.0f64; 4];
    let n4 = x.len() / 4 * 4;
    for ((xc, vc), wc) in x[..n4]
        .chunks_exact(4)
        .zip(v[..n4].chunks_exact(4))
        .zip(w2[..n4].chunks_exact(4))
    {
        for k in 0..4 {
            acc[k] += vc[k] * vc[k] + wc[k] * xc[k] * xc[k];
        }
    }
    for n in n4..x.len() {
        acc[0] += v[n] * v[n] + w2[n] * x[n] * x[n];
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// max(|y0|, |y1|) + c (|ẏ0| + |ẏ1|), c = 4/27·len: a bound of the cubic Hermite
/// interpolant of (y, ẏ) over an interval of length len (its value basis functions are ≥ 0
/// and sum to 1, its slope basis functions are at most 4/27·len in size).
#[inline(always)]
fn cubic_bound(y0: f64, yd0: f64, y1: f64, yd1: f64, c: f64) -> f64 {
    y0.abs().max(y1.abs()) + c * (yd0.abs() + yd1.abs())
}

/// The sample buffers of one building (leading zero, padded floors; see [`Stepper::u`]):
/// values and rates now (`u`, `ud`) and at the previous sample (`up`, `udp`).
struct Sample<'s> {
    u: &'s [f64],
    ud: &'s [f64],
    up: &'s [f64],
    udp: &'s [f64],
    k: &'s [f64],
    /// Length of the interval since the previous sample, s.
    len: f64,
}

/// Floors per word of turn bits of [`sample`].
const TURN_GROUP: usize = 32;

/// The turn bit of the displacement of floor f of a group (1 << 2f) and of its story
/// shear (1 << (2f + 1)), as f64 bit patterns (for vector selects and ors, bitwise only).
static TURN_D: [f64; TURN_GROUP] = turn_bits(0);
static TURN_S: [f64; TURN_GROUP] = turn_bits(1);

const fn turn_bits(story: u32) -> [f64; TURN_GROUP] {
    let mut w = [0.0; TURN_GROUP];
    let mut f = 0;
    while f < TURN_GROUP {
        w[f] = f64::from_bits(1 << (2 * f as u32 + story));
        f += 1;
    }
    w
}

/// The sample of one building, branch-free over its (padded) floors in vectors of `simd`:
/// the running peaks of |u_i| and |V_i| = |k_i (u_i − u_{i−1})| (`dm`, `sm`), and which
/// quantities' rates ẏ change sign over the interval (rare: only those may have an interior
/// extremum, [`Stepper::interior_extremum`]): `turn` receives, as u64 bit patterns, one
/// word per group of [`TURN_GROUP`] floors whose bit 2f is set if the displacement of
/// floor f of the group turns and bit 2f + 1 if its story shear does. Returns (a peak was
/// raised, some rate changes sign). The padding floors are zeros and never raise or flag
/// anything.
#[inline(always)]
fn sample<S: pulp::Simd>(
    simd: S,
    s: Sample<'_>,
    dm: &mut [f64],
    sm: &mut [f64],
    turn: &mut [f64],
) -> (bool, bool) {
    let n = dm.len();
    let (dm, dmt) = S::as_mut_simd_f64s(dm);
    let (sm, smt) = S::as_mut_simd_f64s(&mut sm[..n]);
    let (u, ut) = S::as_simd_f64s(&s.u[1..=n]);
    let (below, belowt) = S::as_simd_f64s(&s.u[..n]);
    let (ud, udt) = S::as_simd_f64s(&s.ud[1..=n]);
    let (vbelow, vbelowt) = S::as_simd_f64s(&s.ud[..n]);
    let (udp, udpt) = S::as_simd_f64s(&s.udp[1..=n]);
    let (pbelow, pbelowt) = S::as_simd_f64s(&s.udp[..n]);
    let (u0, u0t) = S::as_simd_f64s(&s.up[1..=n]);
    let (ubelow, ubelowt) = S::as_simd_f64s(&s.up[..n]);
    let (k, kt) = S::as_simd_f64s(&s.k[..n]);
    let (wd, _) = S::as_simd_f64s(&TURN_D);
    let (ws, _) = S::as_simd_f64s(&TURN_S);
    let m = dm.len();
    let sm = &mut sm[..m];
    let (u, below, ud, vbelow) = (&u[..m], &below[..m], &ud[..m], &vbelow[..m]);
    let (udp, pbelow, k) = (&udp[..m], &pbelow[..m], &k[..m]);
    let (u0, ubelow) = (&u0[..m], &ubelow[..m]);
    let (zero, one) = (simd.splat_f64s(0.0), simd.splat_f64s(1.0));
    let mut rv = simd.less_than_f64s(one, zero);
    // Whether the cubic Hermite interpolant of a quantity over the interval turns twice
    // inside it while its rate has one sign at both ends ([`DoubleTurn`]).
    let two_turns = DoubleTurn::new(simd, s.len);
    // Vector i of the floors: its peaks, and its turn bits (weights `wd`, `ws`).
    // (A macro, not a closure: closures do not inherit the instruction set.)
    macro_rules! step {
        ($i:expr, $wd:expr, $ws:expr) => {{
            let i = $i;
            let d = simd.abs_f64s(u[i]);
            let up = simd.greater_than_f64s(d, dm[i]);
            dm[i] = simd.select_f64s(up, d, dm[i]);
            let y1s = simd.mul_f64s(k[i], simd.sub_f64s(u[i], below[i]));
            let vs = simd.abs_f64s(y1s);
            let us = simd.greater_than_f64s(vs, sm[i]);
            sm[i] = simd.select_f64s(us, vs, sm[i]);
            rv = simd.or_m64s(rv, simd.or_m64s(up, us));
            // A rate that changes sign over the interval (rare): the slow path runs only then,
            // or when it may turn twice near the peak (see `double_turn`).
            let r0 = simd.mul_f64s(k[i], simd.sub_f64s(udp[i], pbelow[i]));
            let r1 = simd.mul_f64s(k[i], simd.sub_f64s(ud[i], vbelow[i]));
            let d_turn = simd.less_than_f64s(simd.mul_f64s(udp[i], ud[i]), zero);
            let s_turn = simd.less_than_f64s(simd.mul_f64s(r0, r1), zero);
            // The double-turn test (rare to pass its necessary condition: only for vectors
            // with a lane that does).
            let y0s = simd.mul_f64s(k[i], simd.sub_f64s(u0[i], ubelow[i]));
            let may_d = two_turns.may(simd, u0[i], udp[i], u[i], ud[i]);
            let may_s = two_turns.may(simd, y0s, r0, y1s, r1);
            let (d_turn, s_turn) = if any(simd, simd.or_m64s(may_d, may_s)) {
                let d_two = simd.and_m64s(may_d, two_turns.test(simd, u0[i], udp[i], u[i], ud[i]));
                let s_two = simd.and_m64s(may_s, two_turns.test(simd, y0s, r0, y1s, r1));
                (simd.or_m64s(d_turn, d_two), simd.or_m64s(s_turn, s_two))
            } else {
                (d_turn, s_turn)
            };
            simd.or_f64s(
                simd.select_f64s(d_turn, $wd, zero),
                simd.select_f64s(s_turn, $ws, zero),
            )
        }};
    }
    macro_rules! word {
        ($acc:expr) => {{
            let acc = $acc;
            let lanes: &[u64] = pulp::bytemuck::cast_slice(std::slice::from_ref(&acc));
            lanes.iter().fold(0, |a, &x| a | x)
        }};
    }
    // Vectors per word (the lanes divide TURN_GROUP).
    let per = wd.len();
    let mut any_turn = 0;
    let words = if m <= per {
        // One word (buildings of up to TURN_GROUP floors).
        let (wd, ws) = (&wd[..m], &ws[..m]);
        let mut acc = zero;
        for i in 0..m {
            acc = simd.or_f64s(acc, step!(i, wd[i], ws[i]));
        }
        let w = word!(acc);
        turn[0] = f64::from_bits(w);
        any_turn |= w;
        1
    } else {
        let mut g = 0;
        for g0 in (0..m).step_by(per) {
            let mut acc = zero;
            for i in g0..(g0 + per).min(m) {
                acc = simd.or_f64s(acc, step!(i, wd[i - g0], ws[i - g0]));
            }
            let w = word!(acc);
            turn[g] = f64::from_bits(w);
            any_turn |= w;
            g += 1;
        }
        g
    };
    let mut raised = false;
    if !dmt.is_empty() {
        // The floors past the vectors (their words from 0 if not begun above).
        turn[words..n.div_ceil(TURN_GROUP)].fill(0.0);
    }
    let f0 = n - dmt.len(); // the first floor of the tail
    for i in 0..dmt.len() {
        let d = ut[i].abs();
        raised |= d > dmt[i];
        dmt[i] = if d > dmt[i] { d } else { dmt[i] };
        let vs = (kt[i] * (ut[i] - belowt[i])).abs();
        raised |= vs > smt[i];
        smt[i] = if vs > smt[i] { vs } else { smt[i] };
        let (r0, r1) = (
            kt[i] * (udpt[i] - pbelowt[i]),
            kt[i] * (udt[i] - vbelowt[i]),
        );
        // (The vectors' decision: the necessary condition, then the test.)
        let d_two = two_turns.scalar(u0t[i], udpt[i], ut[i], udt[i]);
        let s_two = two_turns.scalar(
            kt[i] * (u0t[i] - ubelowt[i]),
            r0,
            kt[i] * (ut[i] - belowt[i]),
            r1,
        );
        let (d_turn, s_turn) = (udpt[i] * udt[i] < 0.0 || d_two, r0 * r1 < 0.0 || s_two);
        let f = f0 + i;
        let w = ((d_turn as u64) | (s_turn as u64) << 1) << (2 * (f % TURN_GROUP));
        let t = &mut turn[f / TURN_GROUP];
        *t = f64::from_bits(t.to_bits() | w);
        any_turn |= w;
    }
    (raised | any(simd, rv), any_turn != 0)
}

/// The double-turn flag of a quantity y over an interval of length `len` (defect 18): its
/// rate has one sign at both ends while the cubic Hermite interpolant of (y, ẏ) at the ends
/// turns twice inside ([`peaks::turns_twice`]), tested only where its cheaper necessary
/// condition holds ([`peaks::may_turn_twice`]). In vectors of the sample's instruction set
/// ([`DoubleTurn::may`], [`DoubleTurn::test`]) and for the scalar tails
/// ([`DoubleTurn::scalar`]), by the same operations, so the vectors and the tails decide
/// alike on every instruction set. Used by the building samples ([`sample`]) and by the
/// overlap audit's first pass ([`OverlapPass`]).
struct DoubleTurn<S: pulp::Simd> {
    len: f64,
    /// 1/len (0 for an interval of length 0, which has no interior: the test is then false,
    /// and the callers ignore such a sample's flags anyway).
    inv_len: f64,
    zero: S::f64s,
    half: S::f64s,
    three_halves: S::f64s,
    two: S::f64s,
    three: S::f64s,
    lenv: S::f64s,
    inv_lenv: S::f64s,
}

impl<S: pulp::Simd> DoubleTurn<S> {
    #[inline(always)]
    fn new(simd: S, len: f64) -> Self {
        let inv_len = if len > 0.0 { 1.0 / len } else { 0.0 };
        DoubleTurn {
            len,
            inv_len,
            zero: simd.splat_f64s(0.0),
            half: simd.splat_f64s(0.5),
            three_halves: simd.splat_f64s(1.5),
            two: simd.splat_f64s(2.0),
            three: simd.splat_f64s(3.0),
            lenv: simd.splat_f64s(len),
            inv_lenv: simd.splat_f64s(inv_len),
        }
    }

    /// [`peaks::may_turn_twice`], lane by lane, the same operations.
    #[inline(always)]
    fn may(&self, simd: S, y0: S::f64s, r0: S::f64s, y1: S::f64s, r1: S::f64s) -> S::m64s {
        let dd = simd.sub_f64s(
            simd.mul_f64s(self.half, simd.add_f64s(r0, r1)),
            simd.mul_f64s(simd.sub_f64s(y1, y0), self.inv_lenv),
        );
        simd.and_m64s(
            simd.less_than_f64s(self.zero, simd.mul_f64s(dd, r0)),
            simd.less_than_f64s(
                simd.min_f64s(simd.abs_f64s(r0), simd.abs_f64s(r1)),
                simd.mul_f64s(self.three_halves, simd.abs_f64s(dd)),
            ),
        )
    }

    /// [`peaks::turns_twice`], lane by lane, the same operations (m0 c3 > 0, m0 c2 < 0,
    /// |c2| < 3|c3| and c2² > 3 m0 c3).
    #[inline(always)]
    fn test(&self, simd: S, y0: S::f64s, r0: S::f64s, y1: S::f64s, r1: S::f64s) -> S::m64s {
        let (two, three, zero) = (self.two, self.three, self.zero);
        let dy = simd.sub_f64s(y1, y0);
        let (m0, m1) = (simd.mul_f64s(r0, self.lenv), simd.mul_f64s(r1, self.lenv));
        let c2 = simd.sub_f64s(
            simd.sub_f64s(simd.mul_f64s(three, dy), simd.mul_f64s(two, m0)),
            m1,
        );
        let c3 = simd.sub_f64s(simd.add_f64s(m0, m1), simd.mul_f64s(two, dy));
        let m0c3 = simd.mul_f64s(m0, c3);
        let a = simd.and_m64s(
            simd.less_than_f64s(zero, m0c3),
            simd.less_than_f64s(simd.mul_f64s(m0, c2), zero),
        );
        let b = simd.and_m64s(
            simd.less_than_f64s(simd.abs_f64s(c2), simd.mul_f64s(three, simd.abs_f64s(c3))),
            simd.less_than_f64s(simd.mul_f64s(three, m0c3), simd.mul_f64s(c2, c2)),
        );
        simd.and_m64s(a, b)
    }

    /// The vectors' decision for one scalar quantity: the necessary condition, then the test.
    #[inline(always)]
    fn scalar(&self, y0: f64, r0: f64, y1: f64, r1: f64) -> bool {
        peaks::may_turn_twice(y0, r0, y1, r1, self.inv_len)
            && peaks::turns_twice(y0, r0, y1, r1, self.len)
    }
}

/// Whether some lane of the mask is set.
#[inline(always)]
fn any<S: pulp::Simd>(simd: S, m: S::m64s) -> bool {
    let v = simd.select_f64s(m, simd.splat_f64s(-1.0), simd.splat_f64s(0.0));
    let lanes: &[u64] = pulp::bytemuck::cast_slice(std::slice::from_ref(&v));
    lanes.iter().fold(0, |a, &x| a | x) != 0
}
