//! Randomized differential tests: many small random scenes built in code (2 or 3 shear sticks
//! of 1–6 floors side by side, contacts at facing floors and sometimes a wall, a random
//! piecewise-linear ground motion), each checked for invariants that hold between
//! independent implementations or runs:
//!
//! 1. the momentum method's peaks with a history (every sample observed) and without (the
//!    energy envelope may skip samples) are bit-identical (the skip is exact by design);
//! 2. the momentum method with all modes and the impulse method (physical coordinates,
//!    adaptive Dormand–Prince, the same impact law) find the same impacts and peaks to the
//!    impulse method's error control;
//! 3. the momentum method's peaks are continuous maxima: the same piecewise-linear record on
//!    a k× finer grid gives the same peaks to round-off (the method is exact between events);
//! 4. the energy audits close (momentum to round-off, impulse to its tolerance), contact
//!    energy is never negative, elastic impacts lose nothing, and every impact achieves c_r;
//! 5. the gap element, adaptive and Newmark at a fine step, runs without panicking, ends Ok or
//!    with a typed error, and its two integrators agree.
//!
//! The seeds are deterministic: `POUND_RANDOM_SEEDS=N` widens the sweep (default 32 seeds,
//! 0 … 31), `POUND_RANDOM_FIRST=S` starts it at seed S, `POUND_RANDOM_SEED=S` runs one seed.
//! A failure prints the seed and the scene. Sweep:
//! `POUND_RANDOM_SEEDS=1000 cargo test --release -p solvers --test random_scenes -- --nocapture`.
//!
//! **What the 1000-seed sweep found, and what is left.** It found two defects of the momentum
//! method, both mended in the release that added this file:
//! - *A closure located on the re-arming band.* After an impact the closure search stayed
//!   shifted by the band `pen` (then 1e-9·max(gap, 1 mm)) for a whole segment; a contact that
//!   rebounded and closed again within it was found at δ = +pen, pen/v late (seed 246: impact
//!   6 at 0.787095 s, 2.07e-10 s late; peaks 8.5e-7 off the impulse method at any tolerance).
//!   Failed: seeds 158, 188, 216, 246, 456, 471, 477, 564, 629, 675, 710, 880, 907, 918.
//!   Now re-armed inside the segment (`Stepper::locate_closures`, `Locator::locate`).
//! - *A held contact cut short by another contact's closure.* The held gaps were left open at
//!   the cut (229 µm in seed 68); the next held segments closed them with enormous forces
//!   whose projections kicked the other contact into millions of closures 2 ns apart: a
//!   `Stalled` error (seeds 62, 68, 184, 292, 404, 433, 460, 544, 651, 733, 794, 796) or an
//!   energy audit off by 1e12 J (seed 796). Now the held gaps are closed at the cut
//!   (`Stepper::close_held_gaps`), and a held phase that does work stops the run.
//!
//! **Held phases, the release after.** A reviewer found that the held-gap projection moved
//! the contact closing at the cut too (into penetration of up to 1.8 mm: seeds 472, 733). The
//! new invariant "every impact is resolved within 1.01 × the band of the contact surface"
//! (`Diagnostics::impact_gap_ratio`, checked on every seed) fails 32 of 1000 seeds without the
//! fix, at up to 2e8 × the band. Chasing it led to three more defects of the held phases,
//! mended together:
//! - the projection now keeps the closing contacts, and any contact it would push through,
//!   where they are (`Stepper::close_held_gaps`);
//! - an impact with held neighbours is one LCP with the held contacts as plastic participants
//!   (`with_held`, in both the momentum and the impulse method). Resolved as an impact
//!   followed by a projection of the held contacts, the projection made the impacting contact
//!   approach again at the same instant, a geometric sequence of impacts (seed 1898); left to
//!   the next held segment, the held contacts' relative velocity had to be cancelled by its
//!   constant forces, 1e14 N over slivers (seed 1204);
//! - held segments are shortened until the held gaps stray at most `momentum.held_tolerance`
//!   (default 1e-6 of max(gap, 1 mm)) at their middle; at the record step they strayed by up
//!   to 4 mm, which a cut then had to project away;
//! - a touching contact found closing at every held segment's start (the mean force over the
//!   segment pushes it in where the instantaneous one lets it go) caps the next held segments
//!   (`adapt_held_cap`; seed 1898 stalled there).
//!
//! Invariant 2 for held contacts changed with them: it used to ask the difference to the
//! impulse method to fall as h² under record refinement; now it asks it to fall tenfold at a
//! 100 times tighter `held_tolerance` (or below the impulse method's error).
//!
//! Before and after on seeds 0 … 999 and, not used while building the fixes, 1000 … 3999:
//!
//! | seeds | release | failing seeds | stalls | runs stopped by an audit | momentum storms | impulse storms | held phases (invariant 2) |
//! |---|---|---|---|---|---|---|---|
//! | 0 … 999 | before | 29 | 1 | 3 audits at 6e-9 … 1.4e-7 | 0 | 3 | 25 (h² criterion) |
//! | 0 … 999 | after | 7 | 0 | 0 | 0 | 0 | 7 (tolerance criterion) |
//! | 1000 … 3999 | before | 85 | 13 | 2 | 1 | 3 | 65 (h² criterion) |
//! | 1000 … 3999 | after | 16 | 2 | 0 | 0 | 0 | 13 (tolerance criterion) |
//! | 0 … 999 | re-closures found (next release) | 7 | 0 | 0 | 0 | 0 | 7 |
//! | 1000 … 3999 | re-closures found (next release) | 9 | 0 | 0 | 0 | 0 | 8 |
//! | 0 … 999 | one closure search (the release after) | 7 | 0 | 0 | 0 | 0 | 7 |
//! | 1000 … 3999 | one closure search (the release after) | 8 | 0 | 0 | 0 | 0 | 7 |
//!
//! (The 1000 … 3999 sweep runs the momentum tests only: `momentum_` as the filter.)
//!
//! **Re-closures after a plastic impact, the release after.** Seed 3582, diagnosed above as a
//! join decided within the holding force's round-off band, was not: the momentum method
//! missed the contact's re-closure. After a plastic impact the floors are at rest against
//! each other with a round-off relative velocity δ̇₀ (±4e-17 m/s), and a compressive relative
//! acceleration closes the contact again microseconds later; the closure search looked for
//! an interior maximum of δ only when δ̇₀ > 0 and from the window's start, so the floors
//! overlapped for up to 0.5 ms where the impulse method holds them. A contact separating
//! slowly that turned and came back within one window was missed likewise (seed 1828, one
//! impact lost). `Locator::locate` now looks for both whatever the sign of δ̇₀
//! (`reclosures_after_a_plastic_impact_are_found`, seeds 574, 1828 and 3582). The same
//! round-off made a touching contact under a separating acceleration close again and again
//! at one instant, the last stall (seed 3927 at the tight tolerance; its direction is now
//! read a moment later: `touching_contacts_separating_from_rest_do_not_stall`). It mended
//! 501, 574, 1204, 1652, 1828 (impact counts), 2174, 2331 and 3927 (the two stalls), 3286,
//! 3582 and 3969; three scenes that passed now miss the tenfold criterion narrowly
//! (196, 433 and 3236 fall 8.7, 8.5 and 8.2 times: they converge, just more slowly), and
//! seed 2309 finds 99 against 120 impacts at the tight tolerance (passed before).
//!
//! **Open contacts audited; touching contacts no longer let through (the release after).**
//! `open_contacts_do_not_overlap` runs the momentum method with its contact audit
//! (`solvers::momentum::solve_audited`: every integrated interval sampled at 32 points,
//! independently of the closure search, for a contact not held whose δ exceeds 2 bands). On
//! the closure search of the release before it found 5 of seeds 0 … 999 (52, 196, 433, 458,
//! 689) with floors through each other, by up to 3.4e6 bands (33 µm into a wall, seed 52).
//! All were touching contacts (δ within the band at a window's start) that the case analysis
//! let through: rising from rest or from a slow approach and falling back within the window
//! (taken for a round-off overlap whatever its height), or dipping, rising and falling again
//! (taken to hold no closure). Reading the direction a moment after the start and closing a
//! contact that rises more than a band mends 21 of the 22 seeds of 4000 that the audit
//! fails without the last rule (3927 is left: 1.4e4 bands 2.8 ms after a cascade of impacts).
//! Against the impulse method, which shares the rule: 52, 1947, 2309 and 3638 now find the
//! same impacts (a seed that overlapped in both methods agreed before only because both let
//! it through); 689, 1164, 2709, 3076 (peaks 4e-7 … 4e-5 apart at either held tolerance) and
//! 3181 (36 against 37 impacts: an approach of 1.01e-4 m/s, just above `capture_velocity`,
//! an impact in one method and a touch in the other) fail now; not diagnosed further.
//!
//! | seeds | release | failing (impulse) | stalls | audit (open contacts) |
//! |---|---|---|---|---|
//! | 0 … 999 | one closure search | 7 | 0 | 5 |
//! | 0 … 999 | touching contacts closed | 7 | 0 | 0 |
//! | 1000 … 3999 | one closure search | 8 | 0 | not run |
//! | 1000 … 3999 | touching contacts closed | 10 | 1 (2331, record refined 2×) | 1 |
//! | 0 … 999 | touching neighbours in the impact | 5 | 0 | 0 |
//! | 1000 … 3999 | touching neighbours in the impact | 6 | 0 | 0 |
//! | 0 … 999 | linear holding forces | 9 | 0 | 0 |
//! | 1000 … 3999 | linear holding forces | 24 | 0 | 0 |
//! | 0 … 999 | held segment lengths | 4 | 0 | 0 |
//! | 1000 … 3999 | held segment lengths | 9 | 0 | 0 |
//! | 0 … 999 | captures at rest re-armed | 4 | 0 | 0 |
//! | 1000 … 3999 | captures at rest re-armed | 10 | 0 | 0 |
//!
//! **Touching neighbours in the impact.** An impact's problem held the impacting and the held
//! contacts; an impulse that pushed a touching neighbour into approach started a sequence of
//! impacts at one instant (the stall of 2331 refined, the different sequences of 460 and
//! 3927). The neighbours now take part in one complementarity problem
//! (`impacts_with_touching_neighbours_are_one_problem`): 460, 689, 1164, 2709, 3076, 3181,
//! 3927 and the stall mended; `make studies` and the robustness sweep bit-identical.
//!
//! Held out (seeds 4000 … 7999, not looked at while building defects 8–10; the momentum
//! tests), the session's starting code against the new: against the impulse method 29 → 22
//! failing (4440, 4670, 4756, 5706, 6860, 7475, 7683 mended, none newly failing); the energy
//! audits 2 → 1 (5706 mended; 7225, an event storm where the impulse method runs);
//! refinement 2 → 3 (4601 and 7225 storm on their record as before; 7478 storms on its record
//! refined 5×: an elastic rattle of a light floor, c_r = 1, 0.3 ms between impacts, at the
//! guard's 2000 impacts/s, which the record's run stays under); the contact audit 0.
//!
//! **Linear holding forces.** Held segments held a constant force, whose steps from segment
//! to segment excited the modes the holding force did not follow: the held scenes converged
//! to the impulse method as the cube root of the held tolerance (7035, held out: 5.1e-2 at
//! the default). Now the force is linear from the instantaneous one, and its jump at the
//! next start is held to the tolerance too (docs/solvers.md, defect 11): the ten held scenes
//! below pass, 7035 is at 2.8e-3; energy audits, refinement and the contact audit clean.
//!
//! **Held segment lengths.** Each held segment was tried at the record step and cut to at
//! most a tenth, so most ended 10 to 20 times inside the held tolerance; now it is first
//! tried at the length the previous one suggests (docs/solvers.md, defect 12). The held
//! scenes' peaks converge more regularly with the tolerance (median fitted slope 0.90 against
//! 0.77 over 1e-5 … 1e-8, seeds 0 … 1499), at about three times the difference at the same
//! tolerance and under half the time; energy audits, refinement, history and the contact
//! audit clean over 0 … 3999.
//!
//! **The round-off band** (docs/solvers.md, defect 15). The contacts' band, below which a
//! gap counts as closed, was 1e-9 · max(gap, 1 mm) in both methods; at 1e-10 the held
//! comparison's floor of about 1e-8 is gone: the thirteen held seeds of 0 … 3999 that failed
//! it (532, 541, 631, 846, 1059, 1135, 1771, 2407, 2805, 3208, 3239, 3487, 3638, at 1.1e-9 …
//! 5.3e-8 at the tight held tolerance) pass at 9.5e-11 … 1.1e-8, and on the held-out seeds
//! 4000 … 7999 4440, 4487, 6064, 6727, 6737 and 7286 pass too (none fails newly); energy
//! audits, refinement, history and the contact audit as before
//! (`the_held_comparison_has_no_band_floor` keeps the fourteen).
//!
//! What the sweeps still fail, and what they failed before (the default seeds pass). Over
//! 0 … 3999 every invariant passes; over the held-out 4000 … 29999 only event storms fail: the
//! energy audits on 7225, 14904 and 19253, refinement on 4601, 7225, 13601, 13871, 14560,
//! 14904, 19253, 23156 and 24913, momentum against impulse on 19253 (refinement and momentum
//! against impulse swept over 0 … 17999 at the three round-off probes, below; every other test
//! over 0 … 9999 in one run on 2026-11-29, `POUND_RANDOM_SEEDS=10000`, 1 756 s on two cores
//! beside other work, over 10000 … 17999 in the two first sweeps below, over 18000 … 21999 at
//! defect 20's code, and over 22000 … 29999 in their first sweeps below).
//! Until the probes were widened, momentum against impulse failed on 6471 and 7228 as well:
//! - Held out 8000 … 9999, first swept on 2026-11-29: four failures, all mended. 9906
//!   (refinement: 87 impacts on the record, 86 on it refined 2×) had two defects of the closure
//!   search, a rattle's re-closure found at the band and a re-closure with δ̇ < 0 at both ends
//!   of its window missed (`a_rattle_is_found_alike_on_refined_records`); 8694 and 9401 (held
//!   comparison, the same difference at every held tolerance) a floor's peak missed where its
//!   rate turned twice inside one sample interval (`double_turns_at_a_peak_are_found`); 9279
//!   (energy audits, no impact: 7.6e-11 of its input) was the check's scale, now with the
//!   static energy ([`momentum_balance`]). docs/solvers.md, defects 16–18.
//! - Held out 10000 … 13999, first swept on 2026-11-29 at defect 19's code (`POUND_RANDOM_FIRST=10000
//!   POUND_RANDOM_SEEDS=4000`): energy audits, the gap element's integrators, the history and the
//!   contact audit 0 failing; refinement 4, momentum against impulse 1, none a defect found.
//!   10245 (refined 2×: 31 against 32 impacts) and 11471 (refined 5×: 89 against 86; against
//!   the impulse method 89 against 90) are chaotic rattles at c_r = 1: the refined record's
//!   run differs from the record's at the first impact by round-off (2.2e-16 s, 1.7e-15 of the
//!   approach speed), and the difference grows impact by impact (10245: 2.5e-11 s at impact 7,
//!   6.5e-9 s at 14, 1.3e-6 s at 22; 11471: 8.6e-11 s at 28, 6.3e-6 s at 56) until an impact
//!   comes or goes. The records refined 5×, 10× and 20× leave 10245's impact 7 within
//!   2.3e-11 … 3.5e-11 s of the record's and 3× on it, converging to no other value: round-off
//!   amplified, not a grid error. The test's own round-off probe (the record scaled by
//!   1 + 4ε) happened to keep their impact counts, so they were not skipped as chaotic (they are
//!   at the three probes, [`ROUND_OFF_PROBES`]). 13601 and
//!   13871 storm on the record refined 5× (13601 with 5 held phases, 240, 189 and 195 impacts
//!   on the record and refined 2× and 3×; 13871 with 80 impacts in 50 ms on its record, the
//!   guard's limit 100, storming at 3× too): sequences near the guard's limit, as 7478 was.
//! - Held out 14000 … 17999, first swept on 2026-11-29 at commit 13cef64 (every test, one run,
//!   896 s): the gap element's integrators, the history and the contact audit 0 failing; energy
//!   audits 1, refinement 3, momentum against impulse 3, none a defect. 14904 storms on its
//!   record (its middle stick's undamped top floor held against one neighbour, rattling against
//!   the other at c_r = 1 every 0.27 ms at 2.1e-3 m/s; 297 impacts with the guard raised, the
//!   impulse method 247 at its default tolerance), failing the energy audits and refinement; 14560 storms on its record
//!   refined 3×. 16436 (refined 5×: peaks 2.3e-10 apart; 170 impacts at c_r = 1, whose times
//!   drift apart from impact 40 on, by 1.8e-7 … 1.5e-6 s at the last over refinements 2× … 32×
//!   in no order) and, against the impulse method, 14587, 17329 and 17441 (impact counts that
//!   do not settle with the impulse method's tolerance; 14587 a near-graze whose instant moves
//!   by up to 2.5e-3 s under round-off, its count kept) are chaotic: the probe 1 + 4ε missed
//!   them (16436's peaks moved 2.9e-13 by it, 1.1e-10 … 1.8e-10 by 1 − 2ε, 1 + ε, 1 + 16ε,
//!   1 + 64ε). Hence the three probes and the moved-impact threshold ([`ROUND_OFF_PROBES`],
//!   [`MOVED_IMPACT`]); the comparison with the impulse method skips a chaotic scene only where
//!   its retries at tighter tolerances cannot close it (1490 and 6016, chaotic by the probes,
//!   are still checked and pass). The peak allowance of both comparisons, 100 times the
//!   response to round-off, is taken over the three probes, so it widened on chaotic scenes
//!   (16436 passes by it). `chaotic_scenes_are_seen_by_the_round_off_probes` keeps the eight
//!   seeds; docs/solvers.md, "Held out 14000 … 17999".
//! - Held out 18000 … 21999, first swept on 2026-11-29 (third session) at commit 9373fdd (every
//!   test, one run, 920 s beside other work): the gap element's integrators, the history and
//!   the contact audit 0 failing; refinement 2, energy audits 1, momentum against impulse 1.
//!   21091 (refined 3×: `Stalled` at 4.2587128 s) was defect 20, a release's round-off rise
//!   taken for a closure again and again (`a_release_with_a_round_off_rise_does_not_stall`).
//!   19253 is an event storm: the middle stick's undamped second floor between a neighbour at
//!   c_r = 0 and a very stiff one at c_r = 1; the momentum method reaches the guard at 3.962 s
//!   (675 impacts with it raised), the impulse method does not (494; 477 and 479 at 1e-11 and
//!   1e-13), their first 22 impacts within 2e-13 s, the 23rd 1.0e-9 s apart, the 34th 5.8e-7 s
//!   (grown through the rattle at c_r = 1), so it fails the energy audits, the comparison and
//!   refinement (its record refined 5× runs). At defect 20's code (526 s) 19253 alone fails.
//! - Held out 22000 … 25999, first swept on 2026-11-29 (third session) at commit 59c34ef (every
//!   test, one run, 893 s): energy audits, momentum against impulse, the history and the
//!   contact audit 0 failing. The gap element's integrators failed 22660 and 24077 on the
//!   balance fallback's two-point ratio (79 and 69 times over 1e-10 … 1e-12, asked 100), now a
//!   fitted slope (`RETRY_SLOPE`; they pass). Refinement failed 23156 and 24913: storms on the
//!   record refined 5× and 3× of scenes with held phases (grid-dependent), where the impulse
//!   method at 1e-8 and 1e-12 finds the momentum method's impacts on each input (23156: 351 on
//!   the record, 1 314 / 1 347 / 1 299 refined; its record's run captures contact 2 at
//!   1.491017 s, the refined run, whose record step the capture reads, at 1.501124 s).
//! - Held out 26000 … 29999, first swept on 2026-11-29 (third session) at commit 0e6d3e5 (every
//!   test, one run, 912 s): refinement failed 27033 on the overlap audit (A4–B4: 4.3e-8 of the
//!   largest displacement against 2.6e-9), every other test passed. Its maximum lies where an
//!   impact turns the floors back and moves with that impact's instant, which its undamped
//!   rattle at c_r = 1 moves under round-off (the probes: 4.6e-9 s, the overlap 3.0e-8, the
//!   peaks 2.6e-11). Overlaps now have their own round-off allowance (`round_off_responses`);
//!   refinement over 0 … 29999 then fails only on the nine storms listed above.
//! - Before defect 15, the thirteen held seeds above, at a floor of about 1e-8 that the held
//!   tolerance did not control (541: 9.7e-9 at 1e-8 and at 1e-10); before defect 12, 32
//!   others (65, 75, 113, 145, 360, 402, 541, 715, 851 and 23 of 1000 … 3999); before linear
//!   forces ten more (196, 433, 540, 733, 949, 1155, 1355, 2100, 3236, 3904, at up to
//!   5.1e-5). All pass now.
//! - Seed 1490 (free flight, no held contacts), listed here for many releases as 135 against 138
//!   impacts "not the impulse method's integration error", was: the impulse method finds 135,
//!   147, 138, 138, 135, 136 and 135 impacts at tolerances 1e-8 … 1e-14, its peaks 1.2e-1,
//!   1.6e-2, 4.0e-2, 1.9e-2, 1.4e-3, 1.6e-4 and 1.6e-5 from the momentum method's, tenfold per
//!   decade from 1e-12 on: it converges to the momentum method's answer, but only past the test's
//!   two extra decades. The test now tries a third (1e-14); 1490 passes, and so does the held-out
//!   6016.
//! - Held out (4000 … 7999): 6471 and 7228 (free flight), where the impulse method's impact count
//!   still changes at 1e-15 (6471: 22, 25, 25, 25, 25, 26, 25 impacts at 1e-9 … 1e-15 against the
//!   momentum method's 26; 7228: 69 … 74 against 74, peaks 1.2e-3 apart at 1e-15) and a round-off
//!   change of the record moves the momentum method's peaks by 3.2e-3 and 3.0e-4 with the same
//!   impacts: chaotic rattles that this comparison cannot close (skipped as chaotic at the three
//!   probes); 7225 (an event storm where the
//!   impulse method at its fine tolerance runs: an elastic rattle against a wall at the guard's
//!   2000 impacts/s, where the impulse method at its default tolerance 1e-8 storms too, at 1.826
//!   s against the momentum method's 1.839 s; with the guard at 1e5/s both run, with 506 and 589
//!   impacts, the impulse method at 1e-8) and 4601 (a storm on its refined record). 4923 (held;
//!   45 impacts at every held tolerance against the impulse method's 46 at 1e-11 and 1e-12) is
//!   the impulse method's error too: at 1e-13 it finds the 45, 1.2e-9 from the momentum method's
//!   peaks, having moved 8.8e-8 from 1e-11; the held comparison now retries the impulse method
//!   two decades tighter when the impacts differ.
//! - The gap element's integrators (`gap_element_integrators_agree`, first swept over 1000 … 7999
//!   in defect 15's release; it does not read the band): 2065 and, held out, 5516 (Newmark's
//!   balance error 1.0e-9 over 44 200 steps and 2.6e-9 over 76 800, above its 16ε per step),
//!   2141, 2315 and 2880 (the adaptive integrator's balance error 1.2e-9 … 3.5e-9 at tolerance
//!   1e-8, 2.5e-10 … 3.7e-10 at 1e-10: 3.3 to 9.6 times smaller, not the ten asked; the errors
//!   change sign between tolerances, and over 1e-6 … 1e-12 they fall about tenfold per decade, to
//!   3.5e-12 … 5.0e-12: the test now retries at 1e-12 and asks a hundredfold below the larger of
//!   the two, which the three pass; since the held-out 22660 and 24077, which fell 79 and 69
//!   times there, it retries at 1e-9, 1e-11 and 1e-12 and asks a fitted slope over 1e-9 …
//!   1e-12 within [0.7, 1.3]: 0.95, 0.90, 0.92, 0.97 and 0.87 for the five). 2065 is Newmark's Newton tolerance, not round-off: at Δt =
//!   1e-4 s the residual of a contact-free step after one solve is 5.4e-11 of its force scale
//!   (median of 13 543 such steps; the acceleration formed from displacement increments cancels),
//!   inside the 1e-10 that accepts it; converged to 1e-13 the balance error is 1.0e-10, but the
//!   paper scene's Newmark run then takes 79 892 Newton iterations instead of 39 968 (its balance
//!   error was round-off already, 3e-13 of the input): not changed. Instead Newmark's audit now
//!   reports the work of the residuals Newton leaves (`EnergyAudit::residual_work`), which the
//!   average-acceleration scheme's exact discrete energy identity makes the balance error less
//!   round-off: 2065's 1.002e-9 all but 3.6e-13, 5516's 2.610e-9 all but 4.7e-12. The check
//!   asks the balance less that work within ε per step (16 times tighter than the 16ε it asked
//!   of the balance; at most 0.28 ε per step over 0 … 7999): all 8000 seeds pass
//!   (`newmark_balance_beyond_round_off_is_its_residual_work` keeps the two).
//! - Tried and not kept: deciding a contact its own plastic impact leaves touching at once
//!   from its holding force, in both methods (docs/solvers.md, "What is left").

mod common;

use common::random::SplitMix64;
use solvers::{History, Method, RunOutput, SolverError};
use structure::testing::{free_scene, refined};
use structure::{Building, Contact, GroundMotion, Scene};

// --- scenes ----------------------------------------------------------------------------------

/// One random scene and its description.
struct Case {
    seed: u64,
    scene: Scene,
    what: String,
}

/// The first (longest) period of `b`, s.
fn first_period(b: &Building) -> f64 {
    b.modes().expect("modes").periods()[0]
}

/// A random building: `n` floors of 1e4 … 1e6 kg, story stiffnesses of a random profile
/// scaled so that the first period is `t1` s, damping ratio 0 … 0.08 (0 one time in five).
fn building(r: &mut SplitMix64, name: &str) -> Building {
    let n = r.int(1, 6);
    let m0 = r.log_uniform(2e4, 5e5);
    let masses: Vec<f64> = (0..n)
        .map(|_| (m0 * r.log_uniform(0.5, 2.0)).clamp(1e4, 1e6))
        .collect();
    // A tapered profile with random factors: stiffer below, within a factor 4 per story.
    let shape: Vec<f64> = (0..n)
        .map(|j| (1.0 - 0.5 * j as f64 / n as f64) * r.log_uniform(0.5, 2.0))
        .collect();
    let zeta = if r.chance(0.2) {
        0.0
    } else {
        r.uniform(0.0, 0.08)
    };
    let t1 = r.log_uniform(0.1, 2.0);
    let trial = Building::new(name, masses.clone(), shape.clone(), zeta);
    // T ∝ k^(−½): scale the profile to the target period.
    let scale = (first_period(&trial) / t1).powi(2);
    Building::new(
        name,
        masses,
        shape.iter().map(|k| k * scale).collect(),
        zeta,
    )
}

fn restitution(r: &mut SplitMix64) -> f64 {
    if r.chance(0.2) {
        r.unit()
    } else {
        r.pick(&[1.0, 0.8, 0.5, 0.0])
    }
}

/// A random piecewise-linear ground acceleration: a few sinusoids (0.3 … 12 Hz) and white
/// noise under a rise–plateau–decay envelope, scaled to a PGA of 1 … 8 m/s².
fn ground(r: &mut SplitMix64) -> GroundMotion {
    let dt = r.pick(&[0.01, 0.02]);
    let len = r.uniform(3.0, 8.0);
    let n = (len / dt).round() as usize + 1;
    let waves: Vec<(f64, f64, f64)> = (0..r.int(2, 8))
        .map(|_| {
            (
                r.log_uniform(0.3, 12.0) * 2.0 * std::f64::consts::PI,
                r.uniform(0.2, 1.0),
                r.uniform(0.0, 2.0 * std::f64::consts::PI),
            )
        })
        .collect();
    let noise = r.uniform(0.0, 0.6);
    let rise = r.uniform(0.05, 0.3) * len;
    let plateau_end = rise + r.uniform(0.1, 0.4) * len;
    let decay = r.uniform(1.0, 4.0) / (len - plateau_end).max(dt);
    let mut accel: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 * dt;
            let env = if t < rise {
                (t / rise).powi(2)
            } else if t < plateau_end {
                1.0
            } else {
                (-(t - plateau_end) * decay).exp()
            };
            let s: f64 = waves.iter().map(|(w, a, p)| a * (w * t + p).sin()).sum();
            env * (s + noise * r.normal())
        })
        .collect();
    let pga = r.uniform(1.0, 8.0);
    let peak = accel.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    for a in &mut accel {
        *a *= pga / peak;
    }
    GroundMotion::new("random", dt, accel).expect("a valid record")
}

/// The scene of `seed`. Valid by construction (the rules of the scene file's validation:
/// contacts join different buildings at floors in range, one contact per floor pair, gaps
/// ≥ 0 and not closed at t = 0 (the buildings start at rest), restitution in [0, 1]).
fn draw(seed: u64) -> Case {
    let mut r = SplitMix64::new(seed);
    let nb = if r.chance(0.2) { 3 } else { 2 };
    let names = ["A", "B", "C"];
    let buildings: Vec<Building> = (0..nb).map(|i| building(&mut r, names[i])).collect();
    let mut contacts = vec![];
    for b in 0..nb - 1 {
        // Without story heights floor i faces floor i; the shorter building's roof is the
        // usual contact, sometimes several facing floors, sometimes one lower floor.
        let facing = buildings[b].n_floors().min(buildings[b + 1].n_floors());
        let floors: Vec<usize> = match r.unit() {
            u if u < 0.6 => vec![facing - 1],
            u if u < 0.85 => {
                let mut f: Vec<usize> = (0..facing - 1).filter(|_| r.chance(0.5)).collect();
                f.push(facing - 1);
                f
            }
            _ => vec![r.int(0, facing - 1)],
        };
        let gap = r.log_uniform(0.005, 0.10);
        let cr = restitution(&mut r);
        let own = r.chance(0.2);
        for f in floors {
            let (gap, cr) = if own {
                (r.log_uniform(0.005, 0.10), restitution(&mut r))
            } else {
                (gap, cr)
            };
            contacts.push(Contact {
                left: b,
                left_dof: f,
                right: b + 1,
                right_dof: f,
                gap,
                restitution: cr,
                wall: false,
                entry: contacts.len(),
            });
        }
    }
    if r.chance(0.15) {
        // A rigid wall right of the last building, at its roof.
        let b = nb - 1;
        let f = buildings[b].n_floors() - 1;
        contacts.push(Contact {
            left: b,
            left_dof: f,
            right: b,
            right_dof: f,
            gap: r.log_uniform(0.005, 0.10),
            restitution: restitution(&mut r),
            wall: true,
            entry: contacts.len(),
        });
    }
    let g = ground(&mut r);
    let duration = (g.accel.len() - 1) as f64 * g.dt;
    let mut scene = free_scene(buildings, contacts, duration);
    scene.name = format!("random-{seed}");
    let pga = g.accel.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    let what = describe(&scene, &g, pga);
    scene.ground = Some(g);
    Case { seed, scene, what }
}

fn describe(s: &Scene, g: &GroundMotion, pga: f64) -> String {
    let mut out = format!(
        "record dt {} s, {:.3} s, PGA {pga:.3} m/s²",
        g.dt, s.duration
    );
    for b in &s.buildings {
        let zeta = match &b.damping {
            structure::Damping::Uniform(z) => *z,
            structure::Damping::PerMode(v) => v[0],
        };
        out += &format!(
            "\n  {}: {} floors, T1 {:.4} s, zeta {zeta:.4}, m {}, k {}",
            b.name,
            b.n_floors(),
            first_period(b),
            b.masses
                .iter()
                .map(|m| format!("{m:.4e}"))
                .collect::<Vec<_>>()
                .join("/"),
            b.story_stiffness
                .iter()
                .map(|k| format!("{k:.4e}"))
                .collect::<Vec<_>>()
                .join("/"),
        );
    }
    for (i, c) in s.contacts.iter().enumerate() {
        let right = if c.wall {
            "wall".to_string()
        } else {
            format!("{}.{}", s.buildings[c.right].name, c.right_dof + 1)
        };
        out += &format!(
            "\n  contact {i}: {}.{} - {right}, gap {:.4} m, c_r {:.4}",
            s.buildings[c.left].name,
            c.left_dof + 1,
            c.gap,
            c.restitution
        );
    }
    out
}

// --- the sweep -------------------------------------------------------------------------------

fn env_u64(key: &str) -> Option<u64> {
    std::env::var(key).ok().and_then(|v| v.trim().parse().ok())
}

/// The seeds of this run (see the module docs).
fn seeds() -> Vec<u64> {
    if let Some(s) = env_u64("POUND_RANDOM_SEED") {
        return vec![s];
    }
    let first = env_u64("POUND_RANDOM_FIRST").unwrap_or(0);
    let n = env_u64("POUND_RANDOM_SEEDS").unwrap_or(32);
    (first..first + n).collect()
}

/// What one invariant found on one seed.
enum Verdict {
    /// Checked: the measured values, named.
    Pass(Vec<(&'static str, f64)>),
    /// Not applicable to this draw, with the reason (counted).
    Skip(String),
    Fail(String),
}

/// Runs `check` on every seed, prints the largest measured values (with their seeds) and the
/// skip reasons, and fails with every failing seed and its scene.
fn sweep(name: &str, check: impl Fn(&Case) -> Verdict) {
    let clock = std::time::Instant::now();
    let seeds = seeds();
    let mut worst: Vec<(&'static str, f64, u64)> = vec![];
    let mut skips: std::collections::BTreeMap<String, Vec<u64>> = Default::default();
    let mut fails = vec![];
    let mut passed = 0;
    for &seed in &seeds {
        let case = draw(seed);
        match check(&case) {
            Verdict::Pass(values) => {
                passed += 1;
                for (k, v) in values {
                    match worst.iter_mut().find(|w| w.0 == k) {
                        Some(w) if v > w.1 || v.is_nan() => *w = (k, v, seed),
                        Some(_) => {}
                        None => worst.push((k, v, seed)),
                    }
                }
            }
            Verdict::Skip(why) => skips.entry(why).or_default().push(seed),
            Verdict::Fail(msg) => fails.push(format!(
                "seed {seed} (POUND_RANDOM_SEED={seed}): {msg}\n  scene: {}",
                case.what
            )),
        }
    }
    eprintln!(
        "{name}: {} seeds, {passed} checked, {} failed, {:.2} s",
        seeds.len(),
        fails.len(),
        clock.elapsed().as_secs_f64()
    );
    for (k, v, s) in &worst {
        eprintln!("  worst {k}: {v:.3e} (seed {s})");
    }
    for (why, s) in &skips {
        let shown: Vec<String> = s.iter().take(12).map(|x| x.to_string()).collect();
        eprintln!("  skipped ({} seeds: {}): {why}", s.len(), shown.join(" "));
    }
    for f in &fails {
        eprintln!("FAIL {f}");
    }
    assert!(
        fails.is_empty(),
        "{name}: {} failing seeds:\n{}",
        fails.len(),
        fails.join("\n")
    );
    // A sweep whose draws are all skipped checks nothing: over eight or more seeds at least a
    // quarter must be checked (the fewest of the sweeps, `refined`, checks 58 % of 0 … 7999).
    assert!(
        seeds.len() < 8 || 4 * passed >= seeds.len(),
        "{name}: only {passed} of {} seeds checked (skips: {skips:?})",
        seeds.len()
    );
}

/// The class of a solver error, for counting.
fn kind(e: &SolverError) -> &'static str {
    match e {
        SolverError::StepSizeUnderflow { .. } => "step size underflow",
        SolverError::NonFinite { .. } => "non-finite",
        SolverError::NewtonFailure { .. } => "Newton failure",
        SolverError::StepBudget { .. } => "step budget",
        SolverError::EventStorm { .. } => "event storm",
        SolverError::SingularContact { .. } => "singular contact",
        SolverError::Refused { .. } => "refused",
        SolverError::Stalled { .. } => "stalled",
        SolverError::Model(_) => "model",
    }
}

// --- comparisons -----------------------------------------------------------------------------

/// Largest relative difference of the peak story shears and floor displacements, and where.
fn peak_diff(a: &RunOutput, b: &RunOutput) -> (f64, String) {
    let mut worst = (0.0, String::new());
    for (x, y) in a.buildings.iter().zip(&b.buildings) {
        let pairs = [
            ("shear", &x.story_shear_max, &y.story_shear_max),
            ("disp", &x.floor_displacement_max, &y.floor_displacement_max),
        ];
        for (what, p, q) in pairs {
            for (j, (p, q)) in p.iter().zip(q.iter()).enumerate() {
                let d = (p - q).abs() / p.abs().max(f64::MIN_POSITIVE);
                if !(d <= worst.0) {
                    worst = (d, format!("{} {what} {}: {p:e} vs {q:e}", x.name, j + 1));
                }
            }
        }
    }
    worst
}

/// Largest overlap-maximum difference relative to the largest floor displacement peak.
fn overlap_diff(a: &RunOutput, b: &RunOutput) -> f64 {
    let scale = a
        .buildings
        .iter()
        .flat_map(|x| x.floor_displacement_max.iter())
        .fold(0.0_f64, |m, v| m.max(*v));
    a.overlaps
        .iter()
        .zip(&b.overlaps)
        .map(|(x, y)| (x.max_overlap - y.max_overlap).abs() / scale)
        .fold(0.0, f64::max)
}

/// Impacts compared: the same count and contacts, the largest |Δt| (s) and the largest
/// velocity difference relative to the approach speed; `Err` names the first mismatch.
fn impact_diff(a: &RunOutput, b: &RunOutput) -> Result<(f64, f64), String> {
    if a.impacts.len() != b.impacts.len() {
        let first = a
            .impacts
            .iter()
            .zip(&b.impacts)
            .position(|(x, y)| x.contact != y.contact || (x.time - y.time).abs() > 1e-6)
            .unwrap_or(a.impacts.len().min(b.impacts.len()));
        let show = |o: &RunOutput| {
            o.impacts.get(first).map_or("none".to_string(), |i| {
                format!(
                    "contact {} at {:.9} s, approach {:.3e} m/s",
                    i.contact, i.time, i.relative_velocity_before
                )
            })
        };
        return Err(format!(
            "{} vs {} impacts; first difference, impact {first}: {} vs {}",
            a.impacts.len(),
            b.impacts.len(),
            show(a),
            show(b)
        ));
    }
    let mut worst = (0.0_f64, 0.0_f64);
    for (k, (x, y)) in a.impacts.iter().zip(&b.impacts).enumerate() {
        if x.contact != y.contact {
            return Err(format!(
                "impact {k}: contact {} at {} s vs contact {} at {} s",
                x.contact, x.time, y.contact, y.time
            ));
        }
        let v = x.relative_velocity_before.abs();
        worst.0 = worst.0.max((x.time - y.time).abs());
        worst.1 = worst
            .1
            .max((x.relative_velocity_before - y.relative_velocity_before).abs() / v)
            .max((x.relative_velocity_after - y.relative_velocity_after).abs() / v);
    }
    Ok(worst)
}

/// Whether a run took a discrete decision whose outcome depends on the record grid by design:
/// a persistent-contact phase (held with forces linear over held segments cut on the record
/// grid), a chattering
/// capture or a touching contact (the capture rule's time scale is the record step; such an
/// impact has no achieved restitution). A capture released at once leaves no phase, so the
/// impacts are looked at too.
fn grid_dependent(o: &RunOutput) -> bool {
    !o.persistent_contacts.is_empty() || o.impacts.iter().any(|i| i.restitution_undefined.is_some())
}

/// `scene` with its record refined `k` times (the same piecewise-linear ground motion).
fn refine(scene: &Scene, k: usize) -> Scene {
    let mut s = scene.clone();
    if k > 1 {
        s.ground = Some(refined(scene.ground.as_ref().unwrap(), k));
    }
    s
}

/// The impulse method on `scene` at tolerance `tol`.
fn impulse_at(scene: &Scene, tol: f64) -> Result<RunOutput, SolverError> {
    let mut s = scene.clone();
    s.gap_element.tolerance = tol;
    solvers::run(&s, Method::Impulse, None)
}

/// Two runs of one check: both outputs, or the verdict when either stopped: a `Skip` when both
/// did (counted), a `Fail` from `fail` (given each outcome, "Ok" or the error) when one did.
fn both_ran(
    a: Result<RunOutput, SolverError>,
    b: Result<RunOutput, SolverError>,
    fail: impl FnOnce(String, String) -> String,
) -> Result<(RunOutput, RunOutput), Verdict> {
    match (a, b) {
        (Ok(a), Ok(b)) => Ok((a, b)),
        (Err(a), Err(b)) => Err(Verdict::Skip(format!(
            "both fail: {} / {}",
            kind(&a),
            kind(&b)
        ))),
        (a, b) => {
            let say =
                |r: Result<RunOutput, SolverError>| r.err().map_or("Ok".into(), |e| e.to_string());
            Err(Verdict::Fail(fail(say(a), say(b))))
        }
    }
}

/// The impulse method on `scene` at `tol`, if it ends and finds `reference`'s impacts (count
/// and contacts): a reference the momentum run can be compared with peak by peak.
fn impulse_matching(scene: &Scene, reference: &RunOutput, tol: f64) -> Option<RunOutput> {
    impulse_at(scene, tol)
        .ok()
        .filter(|i| impact_diff(reference, i).is_ok())
}

/// The round-off-sized changes of [`round_off_response`]: the record scaled by 1 + kε for
/// each k. One probe (k = 4, the only one until held-out seeds 14000 … 17999 were swept) can
/// be an unlucky draw: on 16436 it moved the peaks by 2.9e-13 where k = −2, 1, 16 and 64
/// moved them by 1.1e-10 … 1.8e-10; on 11471 it kept the 89 impacts (peaks 1.8e-3) where
/// k = −8, 2 and 16 gave 92, 91 and 87.
const ROUND_OFF_PROBES: [f64; 3] = [4.0, -2.0, 16.0];

/// An impact that a round-off-sized change moves by more than this, s, counts as moved (the
/// alignment threshold of [`impact_diff`]'s first difference): an ill-conditioned sequence,
/// such as a near-graze whose instant moves by milliseconds (held-out 14587: 111 impacts under
/// every probe, one of them moved by up to 2.5e-3 s; the impulse method finds 110, 113, 111,
/// 113 and 113 at 1e-11 … 1e-15), or a rattle that amplifies round-off impact by impact
/// (17441: by 7.6e-5 … 4.3e-4 s under the three probes).
const MOVED_IMPACT: f64 = 1e-6;

/// The momentum method's response to round-off-sized changes of the scene
/// ([`ROUND_OFF_PROBES`]): its largest relative peak change over the probes, and whether
/// every probe leaves the impacts where they were (the same count and contacts, no instant
/// moved beyond [`MOVED_IMPACT`]). Pounding can be chaotic: a long sequence of impacts
/// amplifies any difference, round-off included, and this measures by how much on the scene
/// at hand.
fn round_off_response(scene: &Scene, mom: &RunOutput) -> (f64, bool) {
    let (pert, _, same) = round_off_responses(scene, mom);
    (pert, same)
}

/// [`round_off_response`] with the overlap audit's own response beside the peaks' (the
/// largest [`overlap_diff`] over the probes). An overlap maximum taken where an impact
/// turns the floors back moves with the impact's instant, far more than the peaks: on
/// held-out seed 27033 (undamped, c_r = 1, 37 impacts) the probes move impact instants by up
/// to 4.6e-9 s and its A4–B4 overlap maximum by 3.0e-8 of the largest displacement, its peaks
/// by 2.6e-11.
fn round_off_responses(scene: &Scene, mom: &RunOutput) -> (f64, f64, bool) {
    let (mut pert, mut pert_overlaps, mut same) = (0.0_f64, 0.0_f64, true);
    for k in ROUND_OFF_PROBES {
        let mut s = scene.clone();
        let g = s.ground.as_mut().unwrap();
        for a in &mut g.accel {
            *a *= 1.0 + k * f64::EPSILON;
        }
        match solvers::run(&s, Method::Momentum, None) {
            Ok(o) => {
                pert = pert.max(peak_diff(mom, &o).0);
                pert_overlaps = pert_overlaps.max(overlap_diff(mom, &o));
                same &= impact_diff(mom, &o).is_ok_and(|(dt, _)| dt <= MOVED_IMPACT);
            }
            Err(_) => return (f64::INFINITY, f64::INFINITY, false),
        }
    }
    (pert, pert_overlaps, same)
}

fn verbose() -> bool {
    std::env::var("POUND_RANDOM_VERBOSE").is_ok()
}

// --- the invariants --------------------------------------------------------------------------

/// Bit-identical peaks with and without a history: the energy envelope's skip is exact.
/// Catches a bound that is not rigorous (a skipped sample that would have raised a peak).
#[test]
fn momentum_peaks_do_not_depend_on_the_history() {
    sweep("history", |c| {
        let plain = match solvers::run(&c.scene, Method::Momentum, None) {
            Ok(o) => o,
            Err(e) => return Verdict::Skip(format!("momentum: {}", kind(&e))),
        };
        let mut h = History::default();
        let full = match solvers::run(&c.scene, Method::Momentum, Some(&mut h)) {
            Ok(o) => o,
            Err(e) => return Verdict::Fail(format!("with a history: {e}, without: Ok")),
        };
        let mut bits = 0.0_f64;
        for (a, b) in plain.buildings.iter().zip(&full.buildings) {
            for (p, q) in a.story_shear_max.iter().zip(&b.story_shear_max).chain(
                a.floor_displacement_max
                    .iter()
                    .zip(&b.floor_displacement_max),
            ) {
                bits = bits.max((p.to_bits() as i64 - q.to_bits() as i64).unsigned_abs() as f64);
            }
        }
        for (a, b) in plain.overlaps.iter().zip(&full.overlaps) {
            bits = bits.max(
                (a.max_overlap.to_bits() as i64 - b.max_overlap.to_bits() as i64).unsigned_abs()
                    as f64,
            );
            if a.time != b.time {
                return Verdict::Fail(format!(
                    "overlap {}.{}-{}.{}: maximum at {} s without a history, {} s with",
                    a.left, a.left_floor, a.right, a.right_floor, a.time, b.time
                ));
            }
        }
        if plain.impacts.len() != full.impacts.len() || plain.overlaps.len() != full.overlaps.len()
        {
            return Verdict::Fail("impacts or overlaps differ with a history".into());
        }
        if bits > 0.0 {
            let (d, at) = peak_diff(&plain, &full);
            return Verdict::Fail(format!(
                "peaks differ by {bits} ulp with a history (relative {d:.3e}, {at})"
            ));
        }
        Verdict::Pass(vec![
            ("ulps", bits),
            ("impacts", plain.impacts.len() as f64),
        ])
    });
}

/// The impulse method's two tolerances: the difference from the momentum method must follow
/// them (its error control), as `impulse.rs` checks on the paper scene.
const TOL_COARSE: f64 = 1e-9;
const TOL_FINE: f64 = 1e-11;

/// Below this relative peak difference the comparison is at the impulse method's error at
/// `TOL_FINE` (100 × the tolerance, as `impulse.rs` and `momentum_peaks.rs` allow on the
/// paper scenes) and no convergence is asked for.
const IMPULSE_FLOOR: f64 = 100.0 * TOL_FINE;

/// The tight `momentum.held_tolerance` of the held-contact comparison (100 × below the
/// default 1e-6).
const HELD_TIGHT: f64 = 1e-8;

/// Momentum (all modes, exact between events) against the impulse method (physical
/// coordinates, adaptive Dormand–Prince, the same impact law).
///
/// Without grid-dependent decisions ([`grid_dependent`]) both integrate the same equations:
/// at `TOL_FINE` the same impacts (count and contacts), and peaks that differ by the impulse
/// method's error: below `IMPULSE_FLOOR`, or at least 10 times closer than at `TOL_COARSE`
/// (100 times the tolerance; the paper scene gives 88, and 30 is asserted there). Catches
/// any error of either method that does not shrink with the tolerance: a wrong motion,
/// impact law or event instant (e.g. a closure located off δ = 0), a missed impact.
///
/// With held contacts the momentum method holds with forces linear over each held segment
/// (from the instantaneous force at its start), its segments shortened until the held gaps
/// stray at most `momentum.held_tolerance` (of max(gap, 1 mm)) inside them and the force's
/// jump at the next start would move them no further; the impulse method holds with the
/// exact instantaneous force.
/// At a 100 times tighter held tolerance ([`HELD_TIGHT`]) the impacts must agree with the
/// impulse method's and the peak difference fall at least tenfold, or below the impulse
/// method's own error. Catches a holding force, projection or release that does not
/// converge to the exact one.
#[test]
fn momentum_matches_the_impulse_method() {
    sweep("impulse", impulse_verdict);
}

/// Invariant 2 on one scene (the sweep's check; [`held_verdict`] with held contacts).
fn impulse_verdict(c: &Case) -> Verdict {
    let (mom, imp) = match both_ran(
        solvers::run(&c.scene, Method::Momentum, None),
        impulse_at(&c.scene, TOL_FINE),
        |a, b| format!("momentum {a} / impulse {b}"),
    ) {
        Ok(pair) => pair,
        Err(v) => return v,
    };
    if !grid_dependent(&mom) && !grid_dependent(&imp) {
        let (pert, same) = round_off_response(&c.scene, &mom);
        let impacts = impact_diff(&mom, &imp);
        // Different impacts where a round-off change moves the momentum method's: chaotic.
        // Skipped only where the comparison below cannot close (seeds 1490 and 6016 are
        // chaotic by the probes and still converge to the momentum method's impacts).
        let chaotic = impacts.is_err() && !same;
        let skip = || Verdict::Skip("chaotic: a round-off change moves the impacts".into());
        let (d, at) = peak_diff(&mom, &imp);
        let coarse = match impulse_at(&c.scene, TOL_COARSE) {
            Ok(o) => peak_diff(&mom, &o).0,
            Err(_) if chaotic => return skip(),
            Err(e) => return Verdict::Fail(format!("impulse at tol {TOL_COARSE:e}: {e}")),
        };
        let o = overlap_diff(&mom, &imp);
        if verbose() {
            eprintln!(
                "seed {}: impacts {} peaks {d:.3e} ({at}) at {TOL_FINE:e}, {coarse:.3e} at \
                 {TOL_COARSE:e}; impacts {impacts:?}, overlaps {o:.3e}",
                c.seed,
                mom.impacts.len(),
            );
        }
        let converging =
            impacts.is_ok() && (d <= IMPULSE_FLOOR || d <= coarse / 10.0 || d <= 100.0 * pert);
        if !converging {
            // Some scenes amplify the integration error so much (stiff undamped sticks
            // rattling through a hundred impacts) that the tolerance is not yet in its
            // asymptotic range at TOL_FINE: two decades further, the same impacts and a
            // difference that still shrinks (at least 3 times per decade, 10 expected),
            // or three decades further, the same impacts and a hundredfold closer.
            let diffs: Vec<Option<f64>> = [TOL_FINE / 10.0, TOL_FINE / 100.0]
                .iter()
                .map(|&tol| impulse_matching(&c.scene, &mom, tol).map(|i| peak_diff(&mom, &i).0))
                .collect();
            let two_decades = match (diffs[0], diffs[1]) {
                (Some(a), Some(b)) => b <= IMPULSE_FLOOR || b <= a / 3.0,
                _ => false,
            };
            if two_decades {
                return Verdict::Pass(vec![("free: converged only below the fine tolerance", 1.0)]);
            }
            // A long elastic rattle can need a third decade: seed 1490 (135 impacts,
            // c_r = 1, an undamped stick) finds 138, 135 and 136 impacts at 1e-11, 1e-12
            // and 1e-13, then the momentum method's 135 at 1e-14 with peaks 1.6e-5 from
            // its (1.9e-2 at 1e-11, 1.4e-3 at 1e-12): the impulse method converging to
            // the momentum method's answer, not yet in its asymptotic range at 1e-13.
            let three_decades =
                impulse_matching(&c.scene, &mom, TOL_FINE / 1000.0).is_some_and(|i| {
                    let e = peak_diff(&mom, &i).0;
                    e <= IMPULSE_FLOOR || e <= d / 100.0
                });
            if !three_decades {
                if chaotic {
                    return skip();
                }
                let what = match impacts {
                    Err(e) => format!("at tol {TOL_FINE:e}: {e}"),
                    Ok(_) => format!(
                        "peaks differ by {coarse:.3e} at tol {TOL_COARSE:e} and {d:.3e} \
                         at {TOL_FINE:e} ({at})"
                    ),
                };
                return Verdict::Fail(format!(
                    "{what}; at tol {:e} and {:e}: {diffs:?}: not the impulse method's \
                     integration error (a round-off change of the record moves the momentum \
                     peaks by {pert:.3e})",
                    TOL_FINE / 10.0,
                    TOL_FINE / 100.0
                ));
            }
            return Verdict::Pass(vec![("free: converged only three decades below", 1.0)]);
        }
        let (dt, dv) = impacts.unwrap();
        let mut v = vec![
            ("free: peaks at the fine tolerance", d),
            ("free: impact times at the fine tolerance (s)", dt),
            ("free: impact velocities / approach", dv),
            ("free: overlaps / largest displacement", o),
        ];
        if d > IMPULSE_FLOOR {
            v.push((
                "free: fine / coarse peak difference (above floor)",
                d / coarse,
            ));
        }
        v.push(("free: round-off response of the peaks", pert));
        return Verdict::Pass(v);
    }
    held_verdict(c, &mom, &imp)
}

/// Invariant 2 with held contacts: the momentum method's held segments keep their gaps within
/// `momentum.held_tolerance`, so at a 100 times tighter one ([`HELD_TIGHT`]) it must find the
/// impulse method's impacts, and peaks at least 10 times closer to the impulse method's, or
/// within the impulse method's own error (its change from [`TOL_COARSE`] to [`TOL_FINE`]).
/// `mom` and `imp` are the momentum run at the default held tolerance and the impulse run at
/// `TOL_FINE`.
fn held_verdict(c: &Case, mom: &RunOutput, imp: &RunOutput) -> Verdict {
    // Held contacts: the momentum method's held segments keep their gaps within
    // momentum.held_tolerance, so its peaks converge to the impulse method's (exact
    // instantaneous forces) as that tolerance falls.
    let mut tight = c.scene.clone();
    tight.momentum.held_tolerance = HELD_TIGHT;
    let mt = match solvers::run(&tight, Method::Momentum, None) {
        Ok(o) => o,
        Err(e) => return Verdict::Fail(format!("momentum at held_tolerance {HELD_TIGHT:e}: {e}")),
    };
    // The impulse method at TOL_FINE may not find the exact impacts yet: two decades further
    // it must (held-out seed 4923: 46 impacts at 1e-11 and 1e-12, the momentum method's 45 at
    // 1e-13, which finds them at every held tolerance), and it is then the reference.
    let mut retried: Option<RunOutput> = None;
    if let Err(e) = impact_diff(&mt, imp) {
        match impulse_matching(&c.scene, &mt, TOL_FINE / 100.0) {
            Some(i) => retried = Some(i),
            // Skipped as chaotic only where the retry cannot close it (as the free scenes).
            None if !round_off_response(&c.scene, &mt).1 => {
                return Verdict::Skip("held, chaotic: a round-off change moves the impacts".into())
            }
            None => {
                return Verdict::Fail(format!(
                    "held contacts, held_tolerance {HELD_TIGHT:e}: {e} (at the impulse \
                     method's tolerances {TOL_FINE:e} and {:e})",
                    TOL_FINE / 100.0
                ))
            }
        }
    }
    // The impulse method's own error at TOL_FINE is at most its change from TOL_COARSE; at
    // TOL_FINE / 100, its change from TOL_FINE.
    let floor = match &retried {
        Some(i) => IMPULSE_FLOOR.max(peak_diff(i, imp).0),
        None => match impulse_at(&c.scene, TOL_COARSE) {
            Ok(o) => IMPULSE_FLOOR.max(peak_diff(imp, &o).0),
            Err(e) => return Verdict::Fail(format!("impulse at tol {TOL_COARSE:e}: {e}")),
        },
    };
    let reference = retried.as_ref().unwrap_or(imp);
    let d_tight = peak_diff(&mt, reference).0;
    let d_default = peak_diff(mom, reference).0;
    if verbose() {
        eprintln!(
            "seed {}: held, peaks {d_default:.3e} at the default held_tolerance, \
             {d_tight:.3e} at {HELD_TIGHT:e}, impulse floor {floor:.3e}",
            c.seed
        );
    }
    // 100 times tighter: at least 10 times closer, or within the impulse method's error.
    let bound = (d_default / 10.0).max(floor);
    if !(d_tight <= bound) {
        return Verdict::Fail(format!(
            "held contacts: peak difference {d_default:.3e} at the default held_tolerance, \
             {d_tight:.3e} at {HELD_TIGHT:e}, above {bound:.3e} (a tenth, or the impulse \
             method's error)"
        ));
    }
    let mut v = vec![
        ("held: peaks at the default held_tolerance", d_default),
        ("held: peaks at the tight held_tolerance", d_tight),
        ("held: tight / bound", d_tight / bound),
    ];
    if retried.is_some() {
        v.push((
            "held: impacts found only at the impulse method's 1e-13",
            1.0,
        ));
    }
    Verdict::Pass(v)
}

/// Relative peak difference allowed between the record and the same record refined: the
/// method is exact between events and locates events to ~2ε·t, so only round-off amplified
/// by the impacts remains (measured up to 7.9e-11 over 1000 seeds where nothing else moves
/// them; `momentum_peaks.rs` allows 1e-11 on the paper scene). Where a round-off change of the
/// record moves the peaks by p (a chaotic sequence of impacts), 100 p is allowed instead.
const REFINED_PEAKS: f64 = 1e-10;

/// The momentum method's peaks are continuous maxima of an exact solution: the same record
/// resampled 2, 3 or 5 times finer (linear interpolation, the same ground motion) changes no
/// impact and no peak beyond round-off. Runs with grid-dependent decisions are skipped
/// (counted): those are grid-dependent by design. Catches peaks taken at samples (a missed
/// interior extremum: the coarse run would be low), event instants or states that depend on
/// the grid (e.g. a base-step split that is not exact).
#[test]
fn momentum_peaks_are_continuous_maxima() {
    sweep("refined", refined_verdict);
}

/// Invariant 3 on one scene (the sweep's check): the record refined 2, 3 or 5 times by seed.
fn refined_verdict(c: &Case) -> Verdict {
    {
        let k = [2, 3, 5][(c.seed % 3) as usize];
        let (a, b) = match both_ran(
            solvers::run(&c.scene, Method::Momentum, None),
            solvers::run(&refine(&c.scene, k), Method::Momentum, None),
            |a, b| format!("record: {a}, refined {k}x: {b}"),
        ) {
            Ok(pair) => pair,
            Err(v) => return v,
        };
        let (d, at) = peak_diff(&a, &b);
        if grid_dependent(&a) || grid_dependent(&b) {
            return Verdict::Skip("held, captured or touching contacts (grid-dependent)".into());
        }
        let (pert, pert_overlaps, same) = round_off_responses(&c.scene, &a);
        let (dt, dv) = match impact_diff(&a, &b) {
            Ok(x) => x,
            Err(_) if !same => {
                return Verdict::Skip("chaotic: a round-off change moves the impacts".into())
            }
            Err(e) => return Verdict::Fail(format!("refined {k}x: {e}")),
        };
        let o = overlap_diff(&a, &b);
        let allowed = REFINED_PEAKS.max(100.0 * pert);
        let allowed_overlaps = REFINED_PEAKS.max(100.0 * pert_overlaps);
        if verbose() {
            eprintln!(
                "seed {} k {k}: impacts {} peaks {d:.3e} ({at}) impact times {dt:.3e} velocities {dv:.3e} overlaps {o:.3e}",
                c.seed,
                a.impacts.len(),
            );
        }
        if !(d <= allowed && o <= allowed_overlaps) {
            return Verdict::Fail(format!(
                "refined {k}x: peaks differ by {d:.3e} ({at}), overlaps by {o:.3e}; a \
                 round-off change of the record moves them by {pert:.3e} and \
                 {pert_overlaps:.3e}"
            ));
        }
        Verdict::Pass(vec![
            ("peaks", d),
            ("round-off response of the peaks", pert),
            ("round-off response of the overlaps", pert_overlaps),
            ("impact times (s)", dt),
            ("impact velocities / approach", dv),
            ("overlaps / largest displacement", o),
        ])
    }
}

/// The eight chaotic seeds that the one round-off probe (record × (1 + 4ε), read by its
/// impact count) missed and that failed the sweeps of 4000 … 17999 (docs/solvers.md, "Held
/// out 14000 … 17999"): at [`ROUND_OFF_PROBES`] and [`MOVED_IMPACT`] refinement skips 10245
/// and 11471 as chaotic and passes 16436 (its peaks 2.3e-10 apart refined 5×, within 100
/// times their response to the probes, 1.8e-10), and the comparison with the impulse method
/// fails none of 6471, 7228, 11471, 14587, 17329 and 17441.
#[test]
fn chaotic_scenes_are_seen_by_the_round_off_probes() {
    let show = |v: &Verdict| match v {
        Verdict::Pass(_) => "passed".to_string(),
        Verdict::Skip(why) => format!("skipped ({why})"),
        Verdict::Fail(why) => format!("failed: {why}"),
    };
    for (seed, want_skip) in [(10245, true), (11471, true), (16436, false)] {
        let c = draw(seed);
        let v = refined_verdict(&c);
        let ok = if want_skip {
            matches!(v, Verdict::Skip(_))
        } else {
            matches!(v, Verdict::Pass(_))
        };
        assert!(ok, "seed {seed}, refinement: {}\n{}", show(&v), c.what);
    }
    for seed in [6471, 7228, 11471, 14587, 17329, 17441] {
        let c = draw(seed);
        let v = impulse_verdict(&c);
        assert!(
            !matches!(v, Verdict::Fail(_)),
            "seed {seed}, against the impulse method: {}\n{}",
            show(&v),
            c.what
        );
    }
}

/// The momentum method's energy balance ([`momentum_balance`]): exact propagation and
/// impacts, so round-off (measured up to 2.5e-12 over seeds 0 … 9999, seed 6241; up to
/// 6.8e-12 over 984 seeds before the static energy was in the scale, where the contact and
/// damping terms cancel; `momentum_paper.rs` allows 1e-12 on the paper scene).
const MOMENTUM_BALANCE: f64 = 5e-11;

/// The momentum method's balance error relative to the larger of input, initial and damping
/// energy plus the static energy of the largest ground load (`Problem::static_energy`), the
/// size of the closed form's terms, as the solver's own audit scales it. Without the static
/// energy, held-out seed 9279 (a 6.5 s record of a stiff stick, T₁ = 0.10 s, beside an
/// undamped one, no impact) measured 7.6e-11 of its 83 J of input, its static energy being
/// about 80 times that: its round-off is about ε of the terms per step (6.3e-9 J over 653
/// steps and 7 modes), not of the energy the record leaves.
fn momentum_balance(scene: &Scene, e: &solvers::EnergyAudit) -> f64 {
    let static_energy = solvers::momentum::Problem::new(scene)
        .expect("the momentum problem")
        .static_energy;
    e.balance_error.abs() / (e.input.abs().max(e.initial).max(e.damping) + static_energy)
}

/// Impacts are computed in closed form: contact energy never negative and zero at c_r = 1,
/// and the achieved restitution c_r, to round-off (relative to the energy scale, and
/// absolute for the restitution; measured up to 3.5e-15 over 1000 seeds).
const IMPACT_ROUNDOFF: f64 = 1e-12;

/// The achieved restitution −v⁺/v⁻ is a ratio of modal sums much larger than a slow approach
/// speed v⁻: its round-off grows as 1/v⁻ (measured up to 1.1e-12 over 1000 seeds).
const RESTITUTION_ROUNDOFF: f64 = 1e-10;

/// An impact is resolved where its closure was located: δ = 0, or δ = `pen` (1e-9 of the
/// gap, at least 1e-12 m) while the contact is not yet re-armed, so |δ| / pen is at most 1
/// plus the root finder's tolerance (2ε·t in time, far below pen / v). Caught the held-gap
/// projection that moved the closing contact too (measured: at most 1.000 over 1000 seeds;
/// without the fix 1.7e3 to 2.0e8 on 32 of them).
const IMPACT_GAP_RATIO: f64 = 1.01;

/// The energy audits and impact books of the momentum and impulse methods. Catches a lost or
/// double-counted work term, an impulse that creates energy or misses c_r, and, for the
/// impulse method, a balance that does not follow its tolerance (within `BALANCE_PER_TOL` ×
/// tol at `TOL_COARSE` and `TOL_FINE`, and ten times smaller at the finer one once above
/// `IMPULSE_FLOOR`).
#[test]
fn energy_audits_close() {
    sweep("energy", |c| {
        let mut values = vec![];
        let mut impulse_balance = [0.0; 2];
        for (method, tol) in [
            (Method::Momentum, TOL_FINE),
            (Method::Impulse, TOL_COARSE),
            (Method::Impulse, TOL_FINE),
        ] {
            let mut s = c.scene.clone();
            s.gap_element.tolerance = tol;
            let run = if method == Method::Momentum {
                solvers::momentum::solve_with_diagnostics(&s, None).map(|(o, d)| (o, Some(d)))
            } else {
                solvers::run(&s, method, None).map(|o| (o, None))
            };
            let (out, diag) = match run {
                Ok(o) => o,
                // A momentum run that stops where the impulse method goes on is a failure
                // (it has no step size or tolerance to blame); otherwise the scene is skipped.
                Err(e)
                    if method == Method::Momentum && impulse_at(&c.scene, TOL_COARSE).is_ok() =>
                {
                    return Verdict::Fail(format!(
                        "momentum stops where the impulse method runs: {e}"
                    ))
                }
                Err(e) => return Verdict::Skip(format!("{method}: {}", kind(&e))),
            };
            let e = &out.energy;
            let scale = e.input.abs().max(e.initial).max(e.damping);
            let balance = e.balance_error.abs() / scale;
            let gained = -e.contact / scale;
            let elastic = s.contacts.iter().all(|c| c.restitution == 1.0);
            let lost = if elastic {
                e.contact.abs() / scale
            } else {
                0.0
            };
            let restitution = out
                .impacts
                .iter()
                .filter(|i| !i.achieved_restitution.is_nan())
                .map(|i| (i.achieved_restitution - s.contacts[i.contact].restitution).abs())
                .fold(0.0, f64::max);
            if verbose() {
                eprintln!(
                    "seed {} {method} {tol:e}: impacts {} held {} balance {balance:.3e} gained {gained:.3e} lost {lost:.3e} restitution {restitution:.3e}",
                    c.seed,
                    out.impacts.len(),
                    out.persistent_contacts.len()
                );
            }
            let what = format!("{method} (tol {tol:e}): ");
            if !(gained <= IMPACT_ROUNDOFF && lost <= IMPACT_ROUNDOFF) {
                return Verdict::Fail(format!(
                    "{what}contact energy {:.6e} J of a scale {scale:.6e} J",
                    e.contact
                ));
            }
            if !(restitution <= RESTITUTION_ROUNDOFF) {
                return Verdict::Fail(format!(
                    "{what}achieved restitution off c_r by {restitution:.3e}"
                ));
            }
            if method == Method::Momentum {
                let balance = momentum_balance(&s, e);
                if !(balance <= MOMENTUM_BALANCE) {
                    return Verdict::Fail(format!(
                        "{what}balance error {balance:.3e} of {scale:.6e} J plus the static energy"
                    ));
                }
                let ratio = diag.map_or(0.0, |d| d.impact_gap_ratio);
                if !(ratio <= IMPACT_GAP_RATIO) {
                    return Verdict::Fail(format!(
                        "{what}an impact resolved at |δ| = {ratio:.3e} × the round-off band"
                    ));
                }
                values.push(("momentum: balance", balance));
                values.push(("momentum: max |δ| / band at an impact", ratio));
                values.push(("momentum: -contact, |contact| at c_r = 1", gained.max(lost)));
                values.push(("momentum: |achieved - c_r|", restitution));
            } else {
                impulse_balance[usize::from(tol == TOL_FINE)] = balance;
                values.push(("impulse: -contact, |contact| at c_r = 1", gained.max(lost)));
                values.push(("impulse: |achieved - c_r|", restitution));
            }
        }
        let [coarse, fine] = impulse_balance;
        values.push(("impulse: balance at the fine tolerance", fine));
        values.push((
            "impulse: balance / tol at the coarse tolerance",
            coarse / TOL_COARSE,
        ));
        values.push((
            "impulse: balance / tol at the fine tolerance",
            fine / TOL_FINE,
        ));
        for (balance, tol) in [(coarse, TOL_COARSE), (fine, TOL_FINE)] {
            if !(balance <= BALANCE_PER_TOL * tol) {
                return Verdict::Fail(format!(
                    "impulse: balance error {balance:.3e} at tol {tol:e}, more than \
                     {BALANCE_PER_TOL:e} × the tolerance"
                ));
            }
        }
        if fine > IMPULSE_FLOOR {
            values.push((
                "impulse: fine / coarse balance (above floor)",
                fine / coarse,
            ));
            if fine > coarse / 10.0 {
                return Verdict::Fail(format!(
                    "impulse: balance error {coarse:.3e} at tol {TOL_COARSE:e}, {fine:.3e} at \
                     {TOL_FINE:e}: it does not follow the tolerance"
                ));
            }
        }
        Verdict::Pass(values)
    });
}

/// The adaptive integrators' energy balance (impulse method, adaptive gap element), relative
/// to the scale of its terms, is their integration error: at most this many times their
/// tolerance, at every tolerance they run at. Measured over seeds 0 … 7999: the impulse
/// method up to 221 × (seed 7973 at 1e-9; 217 × at 1e-11, seed 7924), the adaptive gap
/// element up to 246 × (seed 7312 at 1e-8; 238 × at 1e-10, seed 5720; 5 × at 1e-12 where
/// retried). A margin of four over eight thousand scenes: a balance that stops following the
/// tolerance (a work term integrated apart from the motion) fails it.
const BALANCE_PER_TOL: f64 = 1e3;

/// The band of the fitted slope of the adaptive gap element's balance error against its
/// tolerance (log-log, least squares over 1e-9, 1e-10, 1e-11 and 1e-12) where one decade
/// fails the tenfold fall. The integration error of the balance's terms is proportional to
/// the tolerance (slope 1) whatever the scene's constant; a floor has slope 0.
const RETRY_SLOPE: (f64, f64) = (0.7, 1.3);

/// The least-squares slope of log10 b against log10 tol over `points` (tol, b).
fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .map(|&(t, b)| (t.log10(), b.max(f64::MIN_POSITIVE).log10()))
        .collect();
    let n = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / n,
        xy.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    sxy / sxx
}

/// The slope fit of the retried balance check reads an order and a floor: an exact power
/// law b = C tol^p gives p; a balance with a floor at 1e-11 (1e-11 + 0.1 tol) gives 0.34,
/// below the band's 0.7; the four balances of held-out seed 24077 give 0.866.
#[test]
fn the_balance_slope_fit_reads_orders_and_floors() {
    let tols: [f64; 4] = [1e-9, 1e-10, 1e-11, 1e-12];
    for p in [0.5, 1.0, 2.0] {
        let pts: Vec<(f64, f64)> = tols.iter().map(|&t| (t, 40.0 * t.powf(p))).collect();
        assert!((log_log_slope(&pts) - p).abs() < 1e-12, "order {p}");
    }
    let floor: Vec<(f64, f64)> = tols.iter().map(|&t| (t, 1e-11 + 0.1 * t)).collect();
    assert!(log_log_slope(&floor) < RETRY_SLOPE.0);
    let seed_24077 = [
        (1e-9, 5.742351228144428e-10),
        (1e-10, 9.772156313991838e-11),
        (1e-11, 1.4325221642784807e-11),
        (1e-12, 1.415275303672789e-12),
    ];
    assert!((log_log_slope(&seed_24077) - 0.866).abs() < 1e-3);
}

/// Newmark's step in the comparison with the adaptive gap element, s.
const NEWMARK_STEP: f64 = 1e-4;

/// Largest relative peak difference between Newmark at `NEWMARK_STEP` and the adaptive
/// integrator at tol 1e-10 on the same spring model (Kelvin–Voigt, k = 1e10 N/m). Newmark
/// with contact is not second order here: a closure or opening inside a step (where the
/// dashpot force jumps) costs O(Δt), and its peaks are sampled at the steps; in chaotic
/// pounding the difference does not even fall monotonically with Δt (seed 6: 2.4e-2, 4.3e-3,
/// 5.2e-3, 8.6e-4, 9.3e-4 at Δt = 4e-4 … 2.5e-5 s). Measured up to 0.22 (seed 843) over 1000
/// seeds with the same number of contact episodes; the bound catches a grossly wrong contact
/// law, stiffness, damping or mass in one integrator, not a small drift.
const NEWMARK_PEAKS: f64 = 0.5;

/// The gap element: adaptive (tol 1e-10) and Newmark (`NEWMARK_STEP`) integrate the same
/// spring model. Neither may panic (an error must be a typed `SolverError`, counted); both
/// must close their energy balance (Newmark's, less the work of its Newton residuals, to
/// round-off: ε per step, as `gap_energy.rs` states; the adaptive integrator's must follow
/// its tolerance: within `BALANCE_PER_TOL` × tol at 1e-8 and 1e-10 (and at 1e-9, 1e-11 and
/// 1e-12 where retried), and at least 10 times smaller at tol 1e-10 than at 1e-8, measured
/// 14 to 100 times, or else falling with the tolerance over 1e-9 … 1e-12, a fitted log-log
/// slope within `RETRY_SLOPE`); their
/// peaks must agree to `NEWMARK_PEAKS` when their contact episodes agree in number
/// (near-grazing contacts switch on or off between the integrators: the balances are checked,
/// the seed is counted as skipped).
#[test]
fn gap_element_integrators_agree() {
    sweep("gap", gap_verdict);
}

/// Newmark's balance error less the work of its Newton residuals, relative to the scale of
/// the balance's terms: the round-off of its sums.
fn newmark_rest(o: &RunOutput) -> f64 {
    let e = &o.energy;
    let w = e.residual_work.expect("Newmark reports its residual work");
    (e.balance_error - w).abs() / e.input.abs().max(e.damping).max(e.initial)
}

/// The measured values of a check, named (as in [`Verdict::Pass`]), with the adaptive and
/// Newmark runs of invariant 5.
type GapRuns = (Vec<(&'static str, f64)>, RunOutput, RunOutput);

/// The adaptive and Newmark runs of invariant 5 with their energy balances checked: the
/// measured values and the two runs, or the verdict that ends the check (a skip or a failure).
fn gap_balances(c: &Case) -> Result<GapRuns, Verdict> {
    let mut ad = c.scene.clone();
    ad.gap_element.tolerance = 1e-10;
    let mut loose = c.scene.clone();
    loose.gap_element.tolerance = 1e-8;
    let mut nm = c.scene.clone();
    nm.gap_element.integrator = structure::scene::Integrator::Newmark;
    nm.gap_element.time_step = NEWMARK_STEP;
    let (a, b) = match (
        solvers::run(&ad, Method::Gap, None),
        solvers::run(&nm, Method::Gap, None),
    ) {
        (Ok(a), Ok(b)) => (a, b),
        (a, b) => {
            return Err(Verdict::Skip(format!(
                "adaptive {} / newmark {}",
                a.err().map_or("Ok", |e| kind(&e)),
                b.err().map_or("Ok", |e| kind(&e))
            )))
        }
    };
    let balance = |o: &RunOutput| {
        let e = &o.energy;
        e.balance_error.abs() / e.input.abs().max(e.damping).max(e.initial)
    };
    let (ba, bn) = (balance(&a), balance(&b));
    let steps = (c.scene.duration / NEWMARK_STEP).ceil();
    let bl = match solvers::run(&loose, Method::Gap, None) {
        Ok(o) => balance(&o),
        Err(e) => return Err(Verdict::Skip(format!("adaptive at tol 1e-8: {}", kind(&e)))),
    };
    // The balance's terms are integrated with the motion: its error follows the
    // tolerance (20 to 100 times smaller at a 100 times tighter one measured, 10 asked),
    // whatever the scene's constant (up to 246 × tol measured over seeds 0 … 7999; at most
    // `BALANCE_PER_TOL` × tol asserted). The error changes
    // sign as the tolerance falls, so one ratio can fail where the trend holds (seeds
    // 2141, 2315, 2880: 3.3 to 9.6 times over 1e-8 … 1e-10, about tenfold per decade
    // over 1e-6 … 1e-12): then the fitted slope over 1e-9 … 1e-12 decides (below). Two
    // decades further a hundredfold below the larger of the two, asked before, failed
    // held-out 22660 and 24077, whose errors fall 79 and 69 times from 1e-10 to 1e-12
    // (slopes 0.97 and 0.87 over 1e-9 … 1e-12): the scene's constant moves by tens of per
    // cent between tolerances, so one two-point ratio cannot ask exactly tenfold per decade.
    for (b, tol) in [(bl, 1e-8), (ba, 1e-10)] {
        if !(b <= BALANCE_PER_TOL * tol) {
            return Err(Verdict::Fail(format!(
                "adaptive gap element: balance error {b:.3e} at tol {tol:e}, more than \
                 {BALANCE_PER_TOL:e} × the tolerance"
            )));
        }
    }
    let mut retried = None;
    if ba > 1e-12 && ba > bl / 10.0 {
        // One decade failed the tenfold fall: the trend over the three decades 1e-9 … 1e-12
        // decides, the least-squares slope of log |balance| against log tol, within
        // `RETRY_SLOPE` (a balance that stops following the tolerance has a slope near 0).
        let mut points = vec![(1e-10, ba)];
        for tol in [1e-9, 1e-11, 1e-12] {
            let mut s = c.scene.clone();
            s.gap_element.tolerance = tol;
            let b = match solvers::run(&s, Method::Gap, None) {
                Ok(o) => balance(&o),
                Err(e) => {
                    return Err(Verdict::Skip(format!(
                        "adaptive at tol {tol:e}: {}",
                        kind(&e)
                    )))
                }
            };
            if !(b <= BALANCE_PER_TOL * tol) {
                return Err(Verdict::Fail(format!(
                    "adaptive gap element: balance error {b:.3e} at tol {tol:e}, more than \
                     {BALANCE_PER_TOL:e} × the tolerance"
                )));
            }
            points.push((tol, b));
        }
        points.sort_by(|a, b| b.0.total_cmp(&a.0));
        let slope = log_log_slope(&points);
        if !(RETRY_SLOPE.0..=RETRY_SLOPE.1).contains(&slope) {
            let shown: Vec<String> = points
                .iter()
                .map(|(t, b)| format!("{b:.3e} at {t:e}"))
                .collect();
            return Err(Verdict::Fail(format!(
                "adaptive gap element: balance error {bl:.3e} at tol 1e-8, then {}: slope \
                 {slope:.3} over 1e-9 … 1e-12, outside [{}, {}]",
                shown.join(", "),
                RETRY_SLOPE.0,
                RETRY_SLOPE.1
            )));
        }
        if verbose() {
            eprintln!("seed {}: retried, slope {slope:.3} ({points:?})", c.seed);
        }
        retried = Some((points[3].1, slope));
    }
    // Newmark's balance error is the work of the residuals its Newton iterations leave
    // (`residual_work`, each residual within 1e-10 of the step's force scale) plus the
    // round-off of its sums: less that work, within ε per step (measured at most 0.28 ε per
    // step over seeds 0 … 7999, on 5516). The balance itself stays within 16ε per step where
    // Newton converges to round-off, not on 2065 and 5516 (1.0e-9 and 2.6e-9: 6.4 and 9.6
    // times that).
    let rn = newmark_rest(&b);
    if !(rn <= f64::EPSILON * steps) {
        return Err(Verdict::Fail(format!(
            "Newmark: balance error {bn:.3e}, less its Newton residuals' work {rn:.3e}, over \
             {steps} steps (ε per step: {:.3e})",
            f64::EPSILON * steps
        )));
    }
    if verbose() {
        let (d, at) = peak_diff(&a, &b);
        eprintln!(
            "seed {}: episodes {}/{} peaks {d:.3e} ({at}); balance {ba:.3e} / {bn:.3e}; \
             adaptive {:.3} s, newmark {:.3} s",
            c.seed,
            a.impacts.len(),
            b.impacts.len(),
            a.stats.wall_seconds,
            b.stats.wall_seconds
        );
    }
    let mut v = vec![
        ("adaptive balance at tol 1e-10", ba),
        ("adaptive balance / tol at 1e-8", bl / 1e-8),
        ("adaptive balance / tol at 1e-10", ba / 1e-10),
        ("adaptive balance 1e-10 / 1e-8", ba / bl),
        (
            "newmark balance / (16 eps steps)",
            bn / (16.0 * f64::EPSILON * steps),
        ),
        (
            "newmark (balance - residual work) / (eps steps)",
            rn / (f64::EPSILON * steps),
        ),
    ];
    if let Some((bt, slope)) = retried {
        v.push((
            "adaptive balance slope over 1e-9 … 1e-12, retried: 1 − slope",
            1.0 - slope,
        ));
        v.push((
            "adaptive balance slope over 1e-9 … 1e-12, retried: slope − 1",
            slope - 1.0,
        ));
        v.push(("adaptive balance / tol at 1e-12, retried", bt / 1e-12));
    }
    Ok((v, a, b))
}

/// Invariant 5 on one scene (the sweep's check): the balances ([`gap_balances`]), then the
/// peaks where the two integrators find the same number of contact episodes. Where they do
/// not (near-grazing contacts switch on or off between them) the balances were checked but
/// the peaks cannot be compared: the seed is skipped, not counted as checked.
fn gap_verdict(c: &Case) -> Verdict {
    let (mut v, a, b) = match gap_balances(c) {
        Ok(x) => x,
        Err(verdict) => return verdict,
    };
    if a.impacts.len() != b.impacts.len() {
        return Verdict::Skip(
            "adaptive and Newmark find different numbers of contact episodes (balances \
             checked, peaks not compared)"
                .into(),
        );
    }
    let (d, at) = peak_diff(&a, &b);
    if !(d <= NEWMARK_PEAKS) {
        return Verdict::Fail(format!(
            "Newmark at {NEWMARK_STEP:e} s and the adaptive integrator: peaks differ by {d:.3e} ({at})"
        ));
    }
    v.push(("peaks", d));
    Verdict::Pass(v)
}

/// The regressions' end checks on a momentum run that reached the end: its balance error,
/// relative to the larger of input, initial and damping energy (without the static energy of
/// [`momentum_balance`], so stricter), within [`MOMENTUM_BALANCE`], and every impact resolved
/// within [`IMPACT_GAP_RATIO`] × the band. `what` names the run in the messages.
fn assert_momentum_run_clean(what: &str, out: &RunOutput, d: &solvers::momentum::Diagnostics) {
    let e = &out.energy;
    let balance = e.balance_error.abs() / e.input.abs().max(e.initial).max(e.damping);
    assert!(balance <= MOMENTUM_BALANCE, "{what}: balance {balance:.3e}");
    assert!(
        d.impact_gap_ratio <= IMPACT_GAP_RATIO,
        "{what}: an impact at |δ| = {:.3e} × the band",
        d.impact_gap_ratio
    );
}

/// A contact at rest after a plastic impact with a separating relative acceleration is not
/// closing: random seed 3927 at `momentum.held_tolerance` = 1e-8 (a one-floor building struck
/// from both sides at one instant, contacts at c_r = 0 and 0.79) stopped with `Stalled` at
/// 3.6851 s. Contact 0, touching, had δ̇₀ = −2.8e-17 m/s from the state and +2.8e-17 from
/// the arcs under −0.53 m/s²; the search for its minimum had no bracket and fell back to the
/// window's start, a zero-length closure found again and again at one state. Now it runs to
/// the end (36 impacts, balance 3.1e-14, every impact within 1.0000005 × the band). It does
/// not match the impulse method (48 impacts, peaks 5.2e-4 apart): the floor struck from both
/// sides at one instant is resolved by the impulse method as a sequence of alternating
/// impacts, and a round-off change of the record moves the momentum method's impacts (the
/// differential test skips the scene as chaotic).
#[test]
fn touching_contacts_separating_from_rest_do_not_stall() {
    let case = draw(3927);
    let mut tight = case.scene.clone();
    tight.momentum.held_tolerance = HELD_TIGHT;
    let (out, d) = solvers::momentum::solve_with_diagnostics(&tight, None)
        .unwrap_or_else(|e| panic!("seed 3927: {e}\n{}", case.what));
    assert_momentum_run_clean("seed 3927", &out, &d);
}

/// A contact released at the top of its round-off band, where its relative acceleration is 0
/// (the holding force turning tensile), rises a round-off amount before it falls for good:
/// held-out seed 21091 on its record refined 3× (three sticks, contacts at c_r = 0.8 and 0)
/// stopped with `Stalled` at 4.2587128 s. Released at δ = shift − 1.7e-19 m, the contact's
/// curve rose 1.6e-18 m above its event a moment later; the search took that for a closure
/// at the window's start, the impact step found the contact touching under a tensile holding
/// force and let it graze, which changed nothing, and the same closure was found again
/// (100 032 times). A touching contact just resolved now closes only where it rises a band
/// beyond its event (`closure.rs`, `a_touching_resolved_contact_rising_within_its_band_is_not_closing`).
/// The refined run ends as the record's does (13 impacts, three held phases released by
/// tension, peaks 1.0e-9 apart), its balance closed and every impact within the band.
#[test]
fn a_release_with_a_round_off_rise_does_not_stall() {
    let case = draw(21091);
    let (out, d) = solvers::momentum::solve_with_diagnostics(&refine(&case.scene, 3), None)
        .unwrap_or_else(|e| panic!("seed 21091 refined 3x: {e}\n{}", case.what));
    assert_momentum_run_clean("seed 21091 refined 3x", &out, &d);
    let record = solvers::run(&case.scene, Method::Momentum, None).unwrap();
    assert_eq!(
        out.impacts.len(),
        record.impacts.len(),
        "seed 21091: impacts on the record refined 3x and on the record"
    );
    assert!(out
        .persistent_contacts
        .iter()
        .any(|p| p.released_by == "tension"));
}

/// Regressions of the held-segment fixes, on the seeds where each defect showed (every one
/// runs to the end now):
/// - held gaps closed at a cut without moving other contacts (`Stepper::close_held_gaps`):
///   seeds 52, 472 and 733 resolved impacts 6e7 to 2e8 × the round-off band away from the
///   contact surface (0.6 to 2 mm) when only the held gaps took part in the projection;
/// - a touching contact found closing at every held segment's start (`adapt_held_cap`):
///   seed 1898 stalled at 1.2600003 s.
///
/// Each run must end Ok, resolve every impact within 1.01 × the band, close its audit to
/// [`MOMENTUM_BALANCE`], and (the first three) take at least one gap projection.
#[test]
fn held_segment_regressions_run_clean() {
    for (seed, projects) in [
        (52, true),
        (472, true),
        (733, true),
        (298, false),
        (1898, false),
    ] {
        let case = draw(seed);
        let (out, d) = solvers::momentum::solve_with_diagnostics(&case.scene, None)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}\n{}", case.what));
        assert_momentum_run_clean(&format!("seed {seed}\n{}", case.what), &out, &d);
        assert!(
            !projects || d.gap_projections > 0,
            "seed {seed}: no gap projection (the scene no longer exercises the fix)\n{}",
            case.what
        );
    }
}

/// Regressions of the linear holding forces (docs/solvers.md, defects 11 and 12):
/// - seeds 540 and 733, whose held phases converged to the impulse method's only slowly under
///   constant holding forces (peaks 2.2e-6 and 3.1e-6 apart at the default tolerance, 1.4e-6
///   for 540 at 1e-8), now agree with it to 1.7e-8 and 1.5e-8 at the default held tolerance
///   (asserted: 1e-7), with the same impacts, and in proportion to the held tolerance: 1.9e-10
///   and 2.5e-10 at 1e-8 (asserted: a thirtieth of the default's; 33 and 35 times with the
///   segment lengths of the release before, 2.6e-9 → 7.9e-11 and 3.5e-9 → 1.0e-10);
/// - seed 402, where (while the linear forces were being built, before `Modal::held_arc` and
///   `Arc::ramp_work`) a held segment of 3e-10 s ramped its force steeply and the closed
///   form's cancellation booked −6e8 J to the contact account (the run stopped on its
///   audit): it runs to the end and closes its audit to [`MOMENTUM_BALANCE`]. (The constant
///   forces before passed it: a guard for the new code.)
#[test]
fn linear_holding_forces_regressions() {
    for seed in [540, 733] {
        let (case, mom, imp) = pair(seed, None);
        assert!(
            !mom.persistent_contacts.is_empty(),
            "seed {seed}: no held phase"
        );
        let mut tight = case.scene.clone();
        tight.momentum.held_tolerance = HELD_TIGHT;
        let mt = solvers::run(&tight, Method::Momentum, None)
            .unwrap_or_else(|e| panic!("seed {seed} at {HELD_TIGHT:e}: {e}\n{}", case.what));
        for o in [&mom, &mt] {
            if let Err(e) = impact_diff(o, &imp) {
                panic!("seed {seed}: {e}\n{}", case.what);
            }
        }
        let ((d, at), d_tight) = (peak_diff(&mom, &imp), peak_diff(&mt, &imp).0);
        assert!(
            d < 1e-7 && d_tight <= d / 30.0,
            "seed {seed}: peaks {d:.3e} apart ({at}), {d_tight:.3e} at held tolerance \
             {HELD_TIGHT:e}\n{}",
            case.what
        );
    }
    let case = draw(402);
    let out = solvers::run(&case.scene, Method::Momentum, None)
        .unwrap_or_else(|e| panic!("seed 402: {e}\n{}", case.what));
    let e = &out.energy;
    let balance = e.balance_error.abs() / e.input.abs().max(e.initial).max(e.damping);
    assert!(
        balance <= MOMENTUM_BALANCE,
        "seed 402: balance {balance:.3e}\n{}",
        case.what
    );
}

/// Captures after a plastic impulse (defect 13): a contact left at rest by a plastic impact
/// (c_r = 0), its δ̇ round-off, that separates by more than its round-off band and comes back
/// is re-armed at the minimum and captured where δ = 0 again, as in the impulse method. Read
/// from a round-off δ̇₀ > 0 the momentum method captured it at δ = band instead, late by
/// band/δ̇: seed 541's third phase 5.8e-7 s and sixth 2.4e-6 s after the impulse method's,
/// seed 1135's first 5.6e-6 s. Every phase start now within 5e-8 s of the impulse method's
/// at held tolerance [`HELD_TIGHT`] (measured: 1.2e-8 and 2e-10; what is left follows the
/// release times, whose holding-force bands differ between the methods).
#[test]
fn captures_after_a_plastic_impulse_match_the_impulse_method() {
    for seed in [541, 1135] {
        let (case, mom, imp) = tight_pair(seed);
        assert!(
            !mom.persistent_contacts.is_empty(),
            "seed {seed}: no held phase\n{}",
            case.what
        );
        assert_eq!(
            mom.persistent_contacts.len(),
            imp.persistent_contacts.len(),
            "seed {seed}\n{}",
            case.what
        );
        for (a, b) in mom.persistent_contacts.iter().zip(&imp.persistent_contacts) {
            assert!(
                (a.start - b.start).abs() < 5e-8,
                "seed {seed}: phase start {} against {}\n{}",
                a.start,
                b.start,
                case.what
            );
        }
    }
}

/// The contacts' round-off band (defect 15): at 1e-9 · max(gap, 1 mm) it decided, alike in
/// both methods but not alike at every held tolerance, whether a contact had closed or
/// re-closed, and the held comparison (invariant 2) stopped at about 1e-8. These thirteen
/// seeds of 0 … 3999 failed it there (at the tight held tolerance 1.1e-9 … 5.3e-8, not ten
/// times closer than at the default); with the band at 1e-10 they pass it (9.5e-11 …
/// 1.1e-8), as does the held-out 4440, whose tight run had been 3.8e-7 from the impulse
/// method against 2.6e-6 at the default (3.1e-8 now).
#[test]
fn the_held_comparison_has_no_band_floor() {
    let seeds = [
        532, 541, 631, 846, 1059, 1135, 1771, 2407, 2805, 3208, 3239, 3487, 3638, 4440,
    ];
    for seed in seeds {
        let (case, mom, imp) = pair(seed, None);
        assert!(
            !mom.persistent_contacts.is_empty(),
            "seed {seed}: no held phase (the scene no longer exercises the band)"
        );
        match held_verdict(&case, &mom, &imp) {
            Verdict::Pass(_) => {}
            Verdict::Skip(why) => panic!("seed {seed}: skipped ({why})\n{}", case.what),
            Verdict::Fail(why) => panic!("seed {seed}: {why}\n{}", case.what),
        }
    }
}

/// Held phases between undamped sticks converge as the held tolerance (defect 15): held-out
/// seed 4440 (two undamped buildings, c_r = 1 and 0.01, seven held phases), against the
/// impulse method at [`TOL_FINE`] (its own error about 3e-11 there), at held tolerances
/// 1e-6 … 1e-10: the same 61 impacts at each, and peaks 2.6e-6, 2.9e-7, 3.1e-8, 3.0e-9 and
/// 2.8e-10 apart, a fitted slope of 0.99 (asserted in [0.85, 1.15]). With the round-off
/// band of 1e-9 (both methods then finding 62 impacts, one a re-closure within the band) the
/// peaks stopped converging at 1e-8 (3.8e-7 there; slope 0.60: fails).
#[test]
fn held_phases_of_undamped_sticks_converge_as_the_held_tolerance() {
    let case = draw(4440);
    let imp =
        impulse_at(&case.scene, TOL_FINE).unwrap_or_else(|e| panic!("impulse: {e}\n{}", case.what));
    let tols = [1e-6, 1e-7, 1e-8, 1e-9, 1e-10];
    let diffs: Vec<f64> = tols
        .iter()
        .map(|&tol| {
            let mut s = case.scene.clone();
            s.momentum.held_tolerance = tol;
            let m = solvers::run(&s, Method::Momentum, None)
                .unwrap_or_else(|e| panic!("held tolerance {tol:e}: {e}\n{}", case.what));
            assert!(
                m.persistent_contacts.len() >= 5,
                "held tolerance {tol:e}: {} held phases (the scene no longer exercises them)",
                m.persistent_contacts.len()
            );
            if let Err(e) = impact_diff(&m, &imp) {
                panic!("held tolerance {tol:e}: {e}\n{}", case.what);
            }
            peak_diff(&m, &imp).0
        })
        .collect();
    let slope = common::log_log_slope(&tols, &diffs);
    assert!(
        (0.85..=1.15).contains(&slope),
        "fitted slope {slope:.3} over held tolerances {tols:?}: peaks {diffs:?}"
    );
}

/// Scenes whose comparison needed the impulse method (or the adaptive gap element) at a
/// tighter tolerance than the sweep's first tries, each passing through the sweep's own
/// check and on the branch it needs (the header lists the measurements):
/// - 1490 and the held-out 6016 (free flight): the impulse method finds the momentum method's
///   impacts only at 1e-14, a third decade past `TOL_FINE`;
/// - held-out 4923 (held contacts): at 1e-13 (`held_verdict` retries two decades tighter);
/// - 2141, 2315, 2880 and the held-out 22660 and 24077: the adaptive gap element's balance
///   error falls less than tenfold from tolerance 1e-8 to 1e-10 (its sign changes near 1e-8)
///   and about tenfold per decade over 1e-9 … 1e-12 (fitted slopes 0.95, 0.90, 0.92, 0.97 and
///   0.87; the balance part of the check, [`gap_balances`]).
#[test]
fn comparisons_that_need_a_tighter_reference_pass() {
    let flag = |v: &Verdict, name: &str| match v {
        Verdict::Pass(values) => values.iter().any(|(n, _)| *n == name),
        _ => false,
    };
    for (seed, branch) in [
        (1490, "free: converged only three decades below"),
        (6016, "free: converged only three decades below"),
        (
            4923,
            "held: impacts found only at the impulse method's 1e-13",
        ),
    ] {
        let case = draw(seed);
        let v = impulse_verdict(&case);
        assert!(
            flag(&v, branch),
            "seed {seed}: {branch}: {:?}\n{}",
            kind_of(&v),
            case.what
        );
    }
    // The balance part of invariant 5 (2315's two integrators find 84 and 83 contact
    // episodes, so the sweep then skips its peaks).
    for seed in [2141, 2315, 2880, 22660, 24077] {
        let case = draw(seed);
        let branch = "adaptive balance / tol at 1e-12, retried";
        match gap_balances(&case) {
            Ok((values, _, _)) => assert!(
                values.iter().any(|(n, _)| *n == branch),
                "seed {seed}: not retried: {values:?}\n{}",
                case.what
            ),
            Err(v) => panic!("seed {seed}: {:?}\n{}", kind_of(&v), case.what),
        }
    }
}

/// Seeds 2065 and 5516 (the second held out), where Newmark's energy balance at
/// `NEWMARK_STEP` exceeds its round-off (16ε per step) because Newton accepts a step at a
/// residual within 1e-10 of its force scale: the balance error is the work of those
/// residuals, to round-off (measured: 1.002e-9 of which all but 3.6e-13, and 2.610e-9 of
/// which all but 4.7e-12; asserted: all but 1 % and within ε per step), and the sweep's
/// check passes on both.
#[test]
fn newmark_balance_beyond_round_off_is_its_residual_work() {
    for seed in [2065, 5516] {
        let case = draw(seed);
        let mut nm = case.scene.clone();
        nm.gap_element.integrator = structure::scene::Integrator::Newmark;
        nm.gap_element.time_step = NEWMARK_STEP;
        let o = solvers::run(&nm, Method::Gap, None)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}\n{}", case.what));
        let e = &o.energy;
        let steps = o.stats.steps as f64;
        let balance = e.balance_error.abs() / e.input.abs().max(e.damping).max(e.initial);
        assert!(
            balance > 16.0 * f64::EPSILON * steps,
            "seed {seed}: balance {balance:.3e} is round-off: pick another seed"
        );
        let rest = newmark_rest(&o);
        assert!(
            rest <= 1e-2 * balance && rest <= f64::EPSILON * steps,
            "seed {seed}: balance {balance:.3e}, less the residual work {rest:.3e}"
        );
        let v = gap_verdict(&case);
        assert!(
            matches!(v, Verdict::Pass(_)),
            "seed {seed}: {}\n{}",
            kind_of(&v),
            case.what
        );
    }
}

/// A verdict's kind and message, for a failing assertion.
fn kind_of(v: &Verdict) -> String {
    match v {
        Verdict::Pass(values) => format!("pass {values:?}"),
        Verdict::Skip(why) => format!("skip: {why}"),
        Verdict::Fail(why) => format!("fail: {why}"),
    }
}

/// Seed `seed`'s scene, its momentum run at held_tolerance [`HELD_TIGHT`] and its impulse run
/// at [`TOL_FINE`] (panics, naming the seed, if either stops).
fn tight_pair(seed: u64) -> (Case, RunOutput, RunOutput) {
    pair(seed, Some(HELD_TIGHT))
}

/// Seed `seed`'s scene, its momentum run (at held tolerance `held`, else the scene's own) and
/// its impulse run at [`TOL_FINE`] (panics, naming the seed, if either stops).
fn pair(seed: u64, held: Option<f64>) -> (Case, RunOutput, RunOutput) {
    let case = draw(seed);
    let mut scene = case.scene.clone();
    if let Some(h) = held {
        scene.momentum.held_tolerance = h;
    }
    let mom = solvers::run(&scene, Method::Momentum, None)
        .unwrap_or_else(|e| panic!("seed {seed}: {e}\n{}", case.what));
    let imp = impulse_at(&case.scene, TOL_FINE)
        .unwrap_or_else(|e| panic!("seed {seed}: impulse: {e}\n{}", case.what));
    (case, mom, imp)
}

/// Re-closures of a contact just resolved, within one window: left at rest against its floors
/// by a plastic impact, with a round-off relative velocity δ̇₀ of either sign, it is pressed
/// together again at once and closes microseconds later; separating slowly, it may turn and
/// come back. The closure search looked for an interior maximum of δ only when δ̇₀ > 0 and
/// from the window's start (seed 574: δ̇₀ = −4.2e-17 m/s; seed 3582: +1.4e-17 with δ dipping
/// first; seed 1828: one impact lost, 22 against the impulse method's 23 at the tight
/// tolerance), so the floors overlapped for up to 0.5 ms where the impulse method holds them,
/// and the peaks stayed 3.9e-4 and 1.9e-4 away from the impulse method's at any held
/// tolerance (574, 3582), with one held phase missing. Now (held_tolerance 1e-8 against the
/// impulse method at 1e-11): the same impacts (25, 23, 11) and held phases, starting within
/// 3.4e-8, 2.5e-7 and 5.1e-10 s (asserted: 1e-6 s), and peaks within 3.0e-7, 7.7e-11 and
/// 4.8e-8 (asserted: 1e-6).
#[test]
fn reclosures_after_a_plastic_impact_are_found() {
    for seed in [574, 1828, 3582] {
        let (_, mom, imp) = tight_pair(seed);
        assert_eq!(mom.impacts.len(), imp.impacts.len(), "seed {seed}: impacts");
        let (a, b) = (&mom.persistent_contacts, &imp.persistent_contacts);
        assert_eq!(a.len(), b.len(), "seed {seed}: held phases {a:?}\n{b:?}");
        for (p, q) in a.iter().zip(b) {
            assert!(
                p.contact == q.contact && (p.start - q.start).abs() < 1e-6,
                "seed {seed}: held phase {p:?} against {q:?}"
            );
        }
        let (d, at) = peak_diff(&mom, &imp);
        assert!(d < 1e-6, "seed {seed}: peaks differ by {d:.3e} ({at})");
    }
}

/// The impulse method's closure search is the momentum method's (`closure::Search::locate`,
/// one case analysis over both methods' gap functions). It was a copy without the fixes above
/// (a contact just resolved searched for an interior maximum only when δ̇₀ > 0; a touching
/// contact's direction read from its round-off δ̇₀; no re-arming inside a step), and on seed
/// 3941 the impulse method found a sixth impact (contact 0 at 0.768537153 s, approaching at
/// 1.035e-4 m/s) that the momentum method does not have. Now the same
/// impacts, and peaks 6.9e-9 apart at held_tolerance 1e-8 (asserted: 5e-8; 5.4e-7 at the
/// default tolerance).
#[test]
fn the_impulse_method_shares_the_closure_search() {
    let (case, mom, imp) = tight_pair(3941);
    if let Err(e) = impact_diff(&mom, &imp) {
        panic!("seed 3941: {e}\n{}", case.what);
    }
    let (d, at) = peak_diff(&mom, &imp);
    assert!(d < 5e-8, "seed 3941: peaks differ by {d:.3e} ({at})");
}

/// Largest δ / pen allowed for an open contact at the contact audit's samples: the band pen in
/// which a contact just resolved is searched, plus the rise (at most pen) of a touching contact
/// that the closure search takes for a round-off overlap (`closure::Search::locate`), plus
/// round-off (see `solvers::momentum::audit`).
const OPEN_GAP_RATIO: f64 = 2.01;

/// Open contacts stay open: the momentum method's contact audit samples every integrated
/// interval at 32 points, independently of the closure search, for a contact not held whose
/// floors have gone through each other beyond the round-off band (a missed closure).
#[test]
fn open_contacts_do_not_overlap() {
    sweep("audit", |c| {
        let mut tight = c.scene.clone();
        tight.momentum.held_tolerance = HELD_TIGHT;
        let mut values = vec![];
        for (what, scene) in [("default", &c.scene), ("tight", &tight)] {
            let (out, a) = match solvers::momentum::solve_audited(scene) {
                Ok((o, _, a)) => (o, a),
                Err(e) => return Verdict::Skip(format!("momentum ({what}): {}", kind(&e))),
            };
            if !(a.worst <= OPEN_GAP_RATIO) {
                // The contact's last event before: an impact, or the end of a held phase.
                let impact = out
                    .impacts
                    .iter()
                    .filter(|i| i.contact == a.contact && i.time <= a.time)
                    .map(|i| i.time)
                    .fold(f64::NEG_INFINITY, f64::max);
                let phase = out
                    .persistent_contacts
                    .iter()
                    .rfind(|p| p.contact == a.contact && p.start <= a.time);
                return Verdict::Fail(format!(
                    "held_tolerance {what}: contact {} open at {:.9} s with δ = {:.3e} × its \
                     band ({} intervals audited); its last impact before at {impact:.9} s, \
                     its last held phase {:?}",
                    a.contact,
                    a.time,
                    a.worst,
                    a.intervals,
                    phase.map(|p| (p.start, p.end, &p.released_by))
                ));
            }
            values.push((
                if what == "default" {
                    "open contacts: largest δ / band"
                } else {
                    "open contacts: largest δ / band, tight held tolerance"
                },
                a.worst,
            ));
        }
        Verdict::Pass(values)
    });
}

/// An impact whose impulse pushes a touching neighbour into approach is one complementarity
/// problem with that neighbour (`momentum::impulse::lcp_impulses`), not a sequence of impacts
/// at one instant. Seed 2331 with its record refined twice: a floor between a plastic contact
/// and one at c_r = 0.5, struck from both sides, took impacts alternating at one instant
/// (0.19, 0.095, 0.082 … m/s) until the progress guard stopped the run; it runs to the end.
/// Seed 460 (the same geometry at c_r = 1 and 0): 60 against 63 impacts, now the same impacts
/// in both methods. Seed 3927: a floor 1.4e4 bands into its neighbour after such a cascade,
/// now within the audit's 2 bands.
#[test]
fn impacts_with_touching_neighbours_are_one_problem() {
    let case = draw(2331);
    if let Err(e) = solvers::run(&refine(&case.scene, 2), Method::Momentum, None) {
        panic!("seed 2331 refined twice: {e}\n{}", case.what);
    }
    let (case, mom, imp) = tight_pair(460);
    if let Err(e) = impact_diff(&mom, &imp) {
        panic!("seed 460: {e}\n{}", case.what);
    }
    let case = draw(3927);
    let (_, _, a) = solvers::momentum::solve_audited(&case.scene)
        .unwrap_or_else(|e| panic!("seed 3927: {e}\n{}", case.what));
    assert!(
        a.worst <= OPEN_GAP_RATIO,
        "seed 3927: contact {} at {} s, δ = {:.3e} bands",
        a.contact,
        a.time,
        a.worst
    );
}

#[test]
fn splitmix64_reproduces_the_reference_stream() {
    // Vigna's splitmix64.c seeded with 1234567.
    let mut r = SplitMix64::new(1234567);
    assert_eq!(r.next_u64(), 6457827717110365317);
    assert_eq!(r.next_u64(), 3203168211198807973);
    assert_eq!(r.next_u64(), 9817491932198370423);
}

/// Held-out seed 9906 (two undamped sticks side by side, c_r = 0.8 between them and 0.5 at a
/// wall; two rattles of some 25 impacts each, the second ending at 6.1e-4 m/s), which failed
/// the refinement check of 8000 … 9999 (87 impacts on its record, 86 on the record refined
/// 2×). Two defects of the closure search, both mended: a rattle's flight shorter than the
/// search window was found at δ = band, late by band/δ̇ (impacts 75 and 76, 4.4e-10 s late;
/// `closure.rs`, `a_resolved_contact_that_rebounds_and_closes_within_the_window_is_re_armed`),
/// and a contact re-armed at a step's end that dipped and closed again inside the next window,
/// δ̇ < 0 at both its ends, was missed (the 2× record's impact 77; `closure.rs`,
/// `two_extrema_below_zero_at_both_ends_are_searched`). Now the record and its refinements
/// 2×, 3× and 5× give the same 87 impacts, at times within 1e-9 s of each other (measured
/// 1.4e-10 s) and within 1e-7 s of the impulse method at 1e-12 (measured 7.8e-9 s), every
/// impact resolved within a hundredth of the band of the contact surface (two were on the
/// band before).
#[test]
fn a_rattle_is_found_alike_on_refined_records() {
    let case = draw(9906);
    let (base, diag) = solvers::momentum::solve_with_diagnostics(&case.scene, None)
        .unwrap_or_else(|e| panic!("{e}\n{}", case.what));
    assert_eq!(base.impacts.len(), 87, "{}", case.what);
    assert!(diag.impact_gap_ratio <= 1e-2, "{}", diag.impact_gap_ratio);
    for k in [2, 3, 5] {
        let (out, diag) = solvers::momentum::solve_with_diagnostics(&refine(&case.scene, k), None)
            .unwrap_or_else(|e| panic!("refined {k}x: {e}"));
        let (dt, _) = impact_diff(&base, &out).unwrap_or_else(|e| panic!("refined {k}x: {e}"));
        assert!(dt <= 1e-9, "refined {k}x: impact times {dt:e} s apart");
        assert!(
            diag.impact_gap_ratio <= 1e-2,
            "refined {k}x: {}",
            diag.impact_gap_ratio
        );
    }
    let mut s = case.scene.clone();
    s.gap_element.tolerance = 1e-12;
    let imp = solvers::run(&s, Method::Impulse, None).unwrap();
    let (dt, _) = impact_diff(&base, &imp).unwrap_or_else(|e| panic!("impulse: {e}"));
    assert!(dt <= 1e-7, "impulse: impact times {dt:e} s apart");
}

/// Held-out seeds 8694 and 9401, which failed the held comparison of 8000 … 9999 with the
/// same peak difference at every held tolerance (5.7e-7 and 3.7e-6): a floor displacement
/// whose rate had one sign at both ends of a 5 ms interval turned twice inside it, at its
/// peak (9401: building A's floor, ẏ = −3.3e-4 and −7.9e-5 m/s at the ends, 2.771223e-2 m
/// sampled against 2.771234e-2 m), and only a rate that changes sign was searched. Now the
/// sample also flags a quantity whose rate has one sign at both ends while the cubic Hermite
/// interpolant of its ends turns twice (`peaks::turns_twice`, in `observe::sample`), and the
/// slow path estimates the turn at the cubic's critical point
/// (`peaks::double_turn_estimate`): the momentum method's peaks come within 1e-9
/// (8694, at the default held tolerance; measured 3.0e-10) and 1e-8 (9401, at 1e-8;
/// measured 3.8e-9) of the impulse method's at 1e-11, whose own error is 2.2e-8 and 1.6e-9.
#[test]
fn double_turns_at_a_peak_are_found() {
    for (seed, held, bound) in [(8694, None, 1e-9), (9401, Some(1e-8), 1e-8)] {
        let (case, mom, imp) = pair(seed, held);
        let (d, at) = peak_diff(&mom, &imp);
        assert!(
            d <= bound,
            "seed {seed}: peaks {d:.3e} apart ({at})\n{}",
            case.what
        );
    }
}
