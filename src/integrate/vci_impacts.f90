!> The impact algorithm of a step (paper, Theorem and Algorithm 1; docs/DESIGN.md §1-2): while the
!> regular sub-step's end leaves the admissible set, stage 1 reaches the first wall (bracketing the
!> crossing on the chord or on the discrete trajectory, then Newton on the scheme's stage-1 system),
!> stage 2 reflects with the energy condition (the paper's discrete one, or H kept) and the
!> tangential-momentum conditions on the rest of the sub-step, and the impact is recorded. With
!> several impacts in a step, an impact's energy condition is held on the sub-step that really
!> leaves it (up to the next wall: tie_to_wall), so that a backward run poses the same conditions.
!> A submodule of vci_stepper: it works on the stepper's scheme, Newton and workspace.
submodule (vci_stepper) vci_impacts
  implicit none
  !> The highest stage-polynomial degree stage_screen takes (Lobatto's VCI_LOBATTO_MAX_STAGES);
  !> beyond it, or below 2, the parabola screen
  integer, parameter :: PATH_MAX_DEGREE = 8
  !> The parabola screen's bend, doubled for its margin; and widened to this for whole steps, below
  !> which the other direction's screen cannot dip either (poke_seen_from_end: its half sub-step
  !> lies O(tau^3) from this one's, the margin added is two more bends, O(tau^2))
  real(dp), parameter :: POKE_BEND = 2.0_dp, POKE_FAR_BEND = 4.0_dp

contains

  module subroutine resolve_impacts(self, state, dir, tau, impacts, landed, stat)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(inout) :: state
    integer, intent(in) :: dir
    real(dp), intent(inout) :: tau
    type(vci_impact_buffer_t), intent(inout) :: impacts
    logical, intent(out) :: landed
    integer, intent(out) :: stat
    integer :: n, j, jstar, last_gap, poked
    real(dp) :: h, t, alpha, alpha_j, consumed, e_minus, s1res, p_lo, p_hi, p_glo, p_ghi
    logical :: ok, cleared, tied
    n = self%n; h = state%h; t = state%time()
    consumed = 0.0_dp
    stat = VCI_OK
    landed = .false.
    last_gap = 0
    do
      call self%sys%get_endpoint(self%x, self%q_end)
      call self%sys%eval_gaps(self%q_end, self%gaps_end(1:self%ng), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'gap evaluation'); return
      end if
      ! A wall that the sub-step passes and comes back from within it: where the two directions cut
      ! the motion into different sub-steps (a step with impacts in either), one would meet it at a
      ! sub-step's end and the other not (find_poke). A sub-step with impacts, or ending beyond a
      ! wall, is sampled; a whole step that ends admissible only when the parabola through the
      ! previous step's start says it may come near a wall (gap evaluations only: may_poke).
      poked = 0
      if (.not. self%settings%poke_samples) then
        continue                          ! (switched off: set_poke_samples(.false.))
      else if (impacts%count > 0 .or. any(self%gaps_end(1:self%ng) < 0.0_dp)) then
        call find_poke(self, tau, 0, poked, p_lo, p_hi, p_glo, p_ghi, stat)
      else if (may_poke(self, state, dir, tau, stat)) then
        call find_poke(self, tau, 0, poked, p_lo, p_hi, p_glo, p_ghi, stat, cleared)
        ! a whole step with both ends admissible is the sub-step the other direction starts at its
        ! end: where the screens and samples from the start found no poke, those from the end may,
        ! and the other direction then reflects where this one cannot (poke_seen_from_end). Not
        ! where the screen cleared the step with room to spare (find_poke's cleared)
        if (stat == VCI_OK .and. poked == 0 .and. .not. cleared) then
          if (poke_seen_from_end(self, dir, tau, stat)) &
            self%stats%irreversible_impacts = self%stats%irreversible_impacts + 1
        end if
      end if
      if (stat /= VCI_OK) return
      if (poked == 0 .and. all(self%gaps_end(1:self%ng) >= 0.0_dp)) then
        ! the last impact's motion leaves the rest of the step free: another impulse whose motion
        ! meets a wall may meet its energy row too, and the step then has two solutions
        ! (second_root_exists); its reversal is not guaranteed, and the run says so
        if (last_gap > 0) then
          if (second_root_exists(self, impacts%records(impacts%count), &
                                 real(dir, dp) * impacts%records(impacts%count)%impulse, tau, 0, 0.0_dp, stat)) &
            self%stats%irreversible_impacts = self%stats%irreversible_impacts + 1
          if (stat /= VCI_OK) return
        end if
        exit
      end if
      if (impacts%count >= self%settings%max_impacts_per_step) then
        stat = VCI_ERR_TOO_MANY_IMPACTS
        self%cause = vci_too_many_impacts_cause(self%settings%max_impacts_per_step)
        return
      end if
      call self%sys%eval_gaps(self%q_start, self%gaps_start(1:self%ng), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'gap evaluation at the start of the sub-step'); return
      end if
      call forget_start_gradients(self)         ! (each wall's gradient when first needed)
      call refuse_start_beyond(self, last_gap, stat)
      if (stat /= VCI_OK) return

      ! Already on a wall and moving into it: the impact is at the start of this sub-step.
      jstar = 0
      do j = 1, self%ng
        if (j == last_gap) cycle   ! just reflected there: the motion leaves it (checked in stage 2)
        if (self%gaps_end(j) >= 0.0_dp) cycle
        call start_gradient(self, j, stat)
        if (stat /= VCI_OK) return
        if (on_wall(self, j) .and. dot_product(self%grad_cache(:, self%grad_slot(j)), self%q_end - self%q_start) < 0.0_dp) then
          ! the chord points into the wall; so must the motion as it departs (a curved sub-step
          ! may leave the wall first and come back: that is stage 1's business)
          if (departs_into(self, j, tau, stat)) then
            jstar = j; exit
          end if
          if (stat /= VCI_OK) return
        end if
      end do
      if (jstar > 0) then
        alpha = 0.0_dp
        self%q_wall = self%q_start; self%p_arrive = self%p_start
        if (self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
          ! with constraints, the momentum's admissible part, as impact_momentum gives an impact
          ! inside a step (p_start's Omega-part is no motion; H of it would go into the motion)
          if (self%m > 0) call self%sys%project_momentum(self%q_wall, self%p_arrive, stat)
          if (stat == VCI_OK) call self%sys%hamiltonian(self%q_wall, self%p_arrive, e_minus, stat)
        else
          if (.not. ieee_is_finite(state%arriving_energy)) call arriving_energy(self, dir, h, state%arriving_energy, stat)
          e_minus = state%arriving_energy
        end if
        if (stat /= VCI_OK) then
          call set_cause(self, 'energy of the arriving sub-step'); return
        end if
        s1res = 0.0_dp
        call self%sys%get_multipliers(self%x, self%lambda_start)
        call self%sys%put_multipliers(self%x_stage1, self%lambda_start)
      else
        ! Stage 1 on the violated walls; the first one reached (smallest alpha) is the impact. The
        ! wall the chord crosses first is solved first; then a violated wall is solved only when the
        ! motion up to the wall found so far has already crossed it (its gap is negative at that
        ! stage 1's end): one stage-1 solve for most impacts however many walls the sub-step ends
        ! beyond, not one per violated wall (a chain of n with walls: up to n of them)
        alpha = huge(1.0_dp)
        self%wall_tried(1:self%ng) = .false.
        j = first_by_chord(self, self%gaps_end)
        if (poked > 0) then
          ! the poked wall first: then the walls the end is beyond that the motion crossed before it
          self%wall_tried(poked) = .true.
          call stage_poke(self, poked, tau, p_lo, p_hi, p_glo, p_ghi, alpha_j, ok, stat)
          if (stat /= VCI_OK) return
          if (ok) then
            alpha = alpha_j; jstar = poked
            self%x_stage1(1:self%nsub + 1) = self%x(1:self%nsub + 1)
            s1res = self%last_residual
            call gaps_at_stage1(self, stat)
            if (stat /= VCI_OK) return
            j = first_by_chord(self, self%gaps_trial)
          else
            self%x(1:self%nsub) = self%x_full(1:self%nsub)   ! no crossing found: the sub-step as it was
          end if
        end if
        do while (j > 0)
          self%wall_tried(j) = .true.
          call stage_wall(self, j, tau, alpha_j, stat)
          if (stat /= VCI_OK) return
          if (alpha_j < alpha) then
            alpha = alpha_j; jstar = j
            self%x_stage1(1:self%nsub + 1) = self%x(1:self%nsub + 1)
            s1res = self%last_residual
          end if
          call gaps_at_stage1(self, stat)
          if (stat /= VCI_OK) return
          j = first_by_chord(self, self%gaps_trial)
        end do
        if (jstar == 0) exit      ! a poke stage 1 did not confirm and the end is admissible: no impact
        call reach_crossed_first(self, tau, last_gap, jstar, alpha, s1res, stat)
        if (stat /= VCI_OK) return
        call self%sys%get_endpoint(self%x_stage1, self%q_wall)
        if (self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
          call self%sys%impact_momentum(self%x_stage1, self%q_start, alpha * tau, self%p_arrive, stat, self%p_start)
        else
          ! E- is E_d of these positions; a p- that agrees with it (s D2 L^s of them) keeps grazing
          ! reflections exact (test_stab_grazing)
          call self%sys%momentum_out(self%x_stage1, self%q_start, alpha * tau, self%p_arrive, stat, self%p_start)
        end if
        if (stat == VCI_OK) then
          if (self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
            call self%sys%hamiltonian(self%q_wall, self%p_arrive, e_minus, stat)
          else
            call self%sys%energy_out(self%x_stage1, self%q_start, alpha * tau, e_minus, stat)
          end if
        end if
        if (stat /= VCI_OK) then
          call set_cause(self, 'momentum at the wall'); return
        end if
        ! The previous impact of this step met its energy condition on a sub-step over the whole rest
        ! of the step, but its motion ends here: hold the condition on the sub-step it really leaves on
        if (last_gap > 0) then
          if (impacts%records(impacts%count)%condition == VCI_IMPACT_DISCRETE .or. &
              impacts%records(impacts%count)%condition == VCI_IMPACT_BLENDED) then
            call tie_to_wall(self, impacts%records(impacts%count), dir, tau, jstar, alpha, e_minus, s1res, stat, tied)
            if (stat /= VCI_OK) return
            ! the tied impulse's motion comes back to wall jstar: a larger (or smaller) impulse whose
            ! motion leaves the rest free may meet the whole rest's row too (second_root_exists)
            if (tied) then
              if (second_root_exists(self, impacts%records(impacts%count), &
                                     real(dir, dp) * impacts%records(impacts%count)%impulse, tau, jstar, e_minus, stat)) &
                self%stats%irreversible_impacts = self%stats%irreversible_impacts + 1
              if (stat /= VCI_OK) return
            end if
          end if
        end if
        ! Reached the wall (to round-off) exactly at the end of the step: no reflection yet;
        ! the next step starts on the wall and reflects there.
        call refuse_point_beyond(self, jstar, 1.0_dp - alpha <= landing_fraction, stat)
        if (stat /= VCI_OK) return
        if (1.0_dp - alpha <= landing_fraction) then
          self%q_start = self%q_wall; self%p_start = self%p_arrive
          call self%sys%get_multipliers(self%x_stage1, self%lambda_new)
          self%q_new = self%q_wall; self%p_new = self%p_arrive; self%e_new = e_minus
          state%velocity = real(dir, dp) * (self%q_wall - state%q) / h
          state%predictor_depth = 0
          state%arriving_energy = e_minus
          landed = .true.
          exit
        end if
      end if

      ! Stage 2: reflect from (qt, p_minus) over the rest of the sub-step.
      if (impacts%count == size(impacts%records)) then
        call impacts%reserve(min(2 * size(impacts%records), self%settings%max_impacts_per_step), n, stat)
        if (stat /= VCI_OK) then
          self%cause = 'cannot allocate the record of another impact'; return
        end if
      end if
      self%chord_velocity = (self%q_end - self%q_start) / tau
      call stage_reflect(self, jstar, (1.0_dp - alpha) * tau, e_minus, stat)
      if (stat /= VCI_OK) return
      impacts%count = impacts%count + 1
      call record_impact(self, impacts%records(impacts%count), dir, h, t, consumed + alpha * tau, jstar, e_minus, s1res, &
                         (1.0_dp - alpha) * tau)
      consumed = consumed + alpha * tau
      tau = (1.0_dp - alpha) * tau
      last_gap = jstar
      self%e_arrive_last = e_minus
      self%q_start = self%q_wall
      self%p_start = impacts%records(impacts%count)%p_after
      state%arriving_energy = e_minus
    end do
  end subroutine resolve_impacts

  !> The gaps at stage 1's point (the end of x_stage1, put in q_trial) into gaps_trial.
  subroutine gaps_at_stage1(self, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(out) :: stat
    call self%sys%get_endpoint(self%x_stage1, self%q_trial)
    call self%sys%eval_gaps(self%q_trial, self%gaps_trial(1:self%ng), stat)
    if (stat /= VCI_OK) call set_cause(self, 'gap evaluation at the wall')
  end subroutine gaps_at_stage1

  !> Stage 1 reached wall jstar (x_stage1, its point's gaps in gaps_trial) after crossing a wall whose
  !> gap is positive at the start and at the sub-step's end: a poke that find_poke leaves to stage 1
  !> (its first sample beyond that wall was beyond a wall the end is beyond too), and that stage 1's
  !> walls, those the end is beyond, do not include. The impact is at that wall: its crossing is
  !> bracketed on the trajectory between the start and jstar's point (g > 0 at s = 0, < 0 at alpha)
  !> and solved as a poke; repeated while the new point is beyond another such wall. (A particle
  !> between a floor and a ceiling 0.017 apart, h = 0.087: the side wall reached 1.1e-4 beyond the
  !> ceiling, the state then reflected from there; test_side_wall_beyond_ceiling.)
  subroutine reach_crossed_first(self, tau, last_gap, jstar, alpha, s1res, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: tau
    integer, intent(in) :: last_gap
    integer, intent(inout) :: jstar
    real(dp), intent(inout) :: alpha, s1res
    integer, intent(out) :: stat
    integer :: k, nm
    real(dp) :: alpha_k
    logical :: found
    stat = VCI_OK
    nm = self%nsub
    do
      k = crossed_on_the_way()
      if (k == 0) return
      self%wall_tried(k) = .true.
      call self%sys%get_multipliers(self%x_stage1, self%lambda_start)
      call self%sys%put_endpoint(self%x_low, self%q_start, self%q_start)
      call self%sys%put_multipliers(self%x_low, self%lambda_start)
      self%x_high(1:nm) = self%x_stage1(1:nm)
      call stage_poke(self, k, tau, 0.0_dp, alpha, self%gaps_start(k), self%gaps_trial(k), alpha_k, found, stat)
      if (stat /= VCI_OK) return
      if (.not. (found .and. alpha_k < alpha)) cycle
      alpha = alpha_k; jstar = k
      self%x_stage1(1:nm + 1) = self%x(1:nm + 1)
      s1res = self%last_residual
      call gaps_at_stage1(self, stat)
      if (stat /= VCI_OK) return
    end do
  contains
    !> Of the walls not yet tried, positive at the start and negative at the point reached, the one
    !> the chord to that point crosses first (0: none). The wall just reflected from is not one.
    integer function crossed_on_the_way()
      integer :: i
      real(dp) :: f, best
      crossed_on_the_way = 0
      best = huge(1.0_dp)
      do i = 1, self%ng
        if (i == last_gap .or. self%wall_tried(i)) cycle
        if (.not. (self%gaps_start(i) > 0.0_dp .and. self%gaps_trial(i) < 0.0_dp)) cycle
        f = self%gaps_start(i) / (self%gaps_start(i) - self%gaps_trial(i))
        if (f < best) then
          best = f; crossed_on_the_way = i
        end if
      end do
    end function crossed_on_the_way
  end subroutine reach_crossed_first

  !> Several impacts in one step (docs/DESIGN.md §2, "Several impacts in one step"). Stage 2 of the
  !> previous impact (imp, at q_start) matched E_d over the whole rest tau of the sub-step, but the
  !> motion leaving it reaches wall j after alpha tau: the sub-step that really leaves imp ends there.
  !> E_d depends on the sub-step's length (gravity, springs), so its E_d differs from imp's E-, and a
  !> backward run, which reflects first at wall j, poses the condition on other sub-steps: the
  !> reversal was off by 1e-2 (issue 24). Secant steps on imp's impulse mu until E_d(q_start, wall j,
  !> alpha tau) = E- of imp, the condition both directions pose; each evaluation is a regular
  !> sub-step from p- + mu grad g and stage 1 to wall j. On return stage 1 (x_stage1, q_wall,
  !> p_arrive, alpha, e_minus, s1res) belongs to the final mu, and imp and p_start say so. Where no
  !> impulse meets the condition (near a graze, where E_d hardly depends on mu, or the motion no
  !> longer reaches wall j first), the state of the impulse stage 2 found is put back: that impact keeps
  !> its condition on the whole rest of the step, as before (docs/BACKWARD.md: not reversible).
  subroutine tie_to_wall(self, imp, dir, tau, j, alpha, e_minus, s1res, stat, tied)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_impact_t), intent(inout) :: imp
    integer, intent(in) :: dir, j
    real(dp), intent(in) :: tau
    real(dp), intent(inout) :: alpha, e_minus, s1res
    integer, intent(out) :: stat
    logical, intent(out) :: tied            !< imp's impulse was moved to the tie's root
    integer, parameter :: max_secants = 12
    integer :: k, nx
    real(dp) :: mu_a, mu_b, mu_c, f_a, f_b, f_c, mu_best, f_best, tol, mu_state, alpha0, e0, s10
    logical :: consistent, blend, missed
    stat = VCI_OK
    tied = .false.
    nx = self%nsub
    mu_a = real(dir, dp) * imp%impulse
    ! with H at hand (m = 0) the row is the blended one, as stage 2 posed it (vci_scheme: blended_row)
    blend = self%has_energy .and. self%m == 0
    call tie_row(e_minus, mu_a, f_a, tol)
    if (stat /= VCI_OK) return
    if (abs(f_a) <= 0.01_dp * tol) return      ! free flight: E_d does not depend on the length
    self%tie_x(1:nx + 1, 1) = self%x(1:nx + 1); self%tie_x(1:nx + 1, 2) = self%x_stage1(1:nx + 1)
    self%tie_q(:, 1) = self%q_end; self%tie_q(:, 2) = self%q_wall; self%tie_q(:, 3) = self%p_arrive
    alpha0 = alpha; e0 = e_minus; s10 = s1res
    call self%sys%get_multipliers(self%x, self%lambda_start)
    mu_best = mu_a; f_best = f_a
    mu_state = mu_a; consistent = .true.     ! the stage-1 state in hand belongs to mu_state
    mu_b = mu_a * (1.0_dp + 1.0e-6_dp)
    if (evaluate(mu_b, f_b)) then
      do k = 1, max_secants
        if (abs(f_b) <= 0.01_dp * tol .or. f_b == f_a) exit
        mu_c = mu_b - f_b * (mu_b - mu_a) / (f_b - f_a)
        if (.not. evaluate_towards(mu_b, mu_c, f_c)) exit
        mu_a = mu_b; f_a = f_b; mu_b = mu_c; f_b = f_c
      end do
    end if
    if (stat /= VCI_OK) return
    if (.not. (abs(f_best) <= tol)) then
      ! no root: back to stage 2's impulse and the stage 1 that followed it. A reversed run poses
      ! this impact's condition on the sub-step from wall j, not on the rest of the step: counted
      ! (irreversible_impacts; docs/BACKWARD.md, "Impacts that cannot be tied")
      self%stats%irreversible_impacts = self%stats%irreversible_impacts + 1
      self%x(1:nx + 1) = self%tie_x(1:nx + 1, 1); self%x_stage1(1:nx + 1) = self%tie_x(1:nx + 1, 2)
      self%q_end = self%tie_q(:, 1); self%q_wall = self%tie_q(:, 2); self%p_arrive = self%tie_q(:, 3)
      alpha = alpha0; e_minus = e0; s1res = s10
      self%p_start = imp%p_after
      return
    end if
    ! the state of the evaluation at the best impulse
    if (.not. (consistent .and. mu_state == mu_best)) then
      if (.not. evaluate(mu_best, f_c)) then
        if (stat == VCI_OK) stat = VCI_ERR_IMPACT
        self%cause = 'stage 1 after a change of the previous impulse (several impacts in one step)'
        return
      end if
    end if
    imp%impulse = real(dir, dp) * mu_best
    imp%p_after = imp%p_before + mu_best * imp%grad_g
    imp%energy_after = e_minus
    imp%leave_rate = dot_product(imp%grad_g, self%q_wall - imp%q) / (alpha * tau)
    imp%stage2_residual = abs(f_best) / tol
    if (blend) then
      ! the condition and energies at the tied impulse: blended where the weight is below 1
      call tie_row(e_minus, mu_best, f_c, tol)
      if (stat /= VCI_OK) return
      if (imp%condition == VCI_IMPACT_BLENDED) self%stats%energy_fallbacks = self%stats%energy_fallbacks - 1
      imp%condition = VCI_IMPACT_DISCRETE
      imp%energy_before = self%e_arrive_last
      if (self%sys%blend_w < 1.0_dp) then
        imp%condition = VCI_IMPACT_BLENDED
        imp%energy_before = self%sys%blend_e_before
        imp%energy_after = self%sys%blend_e_after
        self%stats%energy_fallbacks = self%stats%energy_fallbacks + 1
      end if
    end if
    tied = .true.
  contains
    !> The energy row of imp with e_out = E_d of the sub-step leaving it at impulse mu, and its
    !> tolerance: E_d - E- (the discrete condition), or the blended row.
    subroutine tie_row(e_out, mu, f, tol)
      real(dp), intent(in) :: e_out, mu
      real(dp), intent(out) :: f, tol
      real(dp) :: sc
      if (.not. blend) then
        f = e_out - imp%energy_before
        tol = self%settings%atol + self%settings%rtol * (abs(e_out) + abs(imp%energy_before))
        return
      end if
      call self%sys%set_wall_normal(imp%grad_g)
      call self%sys%pose_stage2(imp%q, imp%p_before, tau, imp%gap, self%e_arrive_last)
      call self%sys%pose_blend(stat)
      f = huge(1.0_dp); sc = 0.0_dp
      if (stat == VCI_OK) call self%sys%blended_row(e_out, mu, f, sc, stat)
      if (stat /= VCI_OK) call set_cause(self, 'stage 2: the blended energy condition of the previous impact')
      tol = self%settings%atol + self%settings%rtol * sc
    end subroutine tie_row

    !> evaluate at mu, or, where the motion there misses wall j (a secant step past the impulse at
    !> which it grazes wall j) or mu is not of mu_ok's sign (the reflection's side of mu = 0, as
    !> energy_along keeps it), at mu moved back halfway towards mu_ok (the last impulse that
    !> reached it) until it does: the row's root may lie between (left-rule seed 2892 of the C
    !> harness: the backward tie stopped at such a step and the run ended 2e-2 off its start; with
    !> the halving it finds the root, 8e-15 off). Without the sign, halving from a secant step
    !> through 0 tied left-rule seed 15608's impulse at -0.36: the motion went into the wall it
    !> had left and the next impacts were 1.0e-2 beyond it.
    logical function evaluate_towards(mu_ok, mu, f)
      real(dp), intent(in) :: mu_ok
      real(dp), intent(inout) :: mu
      real(dp), intent(out) :: f
      integer, parameter :: max_halvings = 24
      integer :: k
      evaluate_towards = .false.
      f = huge(1.0_dp)
      do k = 0, max_halvings
        if (mu / mu_ok > 0.0_dp) then
          evaluate_towards = evaluate(mu, f)
          if (evaluate_towards .or. stat /= VCI_OK .or. .not. missed) return
        end if
        mu = 0.5_dp * (mu + mu_ok)
      end do
    end function evaluate_towards

    !> Regular sub-step and stage 1 to wall j from (q_start, p- + mu grad g); f = E_d - E-. False when
    !> the motion misses wall j or a solve fails (stat then says whether that is fatal). Where it
    !> crosses another wall before wall j (crossed_before) its sub-step does not end at wall j: f is
    !> a point for the secant, never the root (mu_best). (Before, such a point either stopped the
    !> search, which cut off the root beyond it in left-rule seed 15608, or, on the wall just left,
    !> went unseen and was taken as the root: reversal seed 35643.)
    logical function evaluate(mu, f)
      real(dp), intent(in) :: mu
      real(dp), intent(out) :: f
      real(dp) :: tol_unused, lo, hi, glo, ghi
      integer :: poked
      logical :: found, crossed
      evaluate = .false.
      consistent = .false.
      missed = .false.
      f = huge(1.0_dp)
      self%p_start = imp%p_before + mu * imp%grad_g
      call self%sys%put_endpoint(self%x, self%q_start, self%q_end)
      call self%sys%put_multipliers(self%x, self%lambda_start)
      call substep(self, self%q_start, self%p_start, tau, stat)
      if (stat /= VCI_OK) return
      call self%sys%get_endpoint(self%x, self%q_end)
      call self%sys%eval_gaps(self%q_end, self%gaps_end(1:self%ng), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'gap evaluation'); return
      end if
      if (self%gaps_end(j) >= 0.0_dp) then
        missed = .true.
        if (.not. self%settings%poke_samples) return
        ! the motion may still pass wall j and come back within the sub-step (find_poke)
        call find_poke(self, tau, j, poked, lo, hi, glo, ghi, stat)
        if (stat /= VCI_OK .or. poked /= j) return
        call stage_poke(self, j, tau, lo, hi, glo, ghi, alpha, found, stat)
        if (stat /= VCI_OK .or. .not. found) return
        missed = .false.
      else
        call stage_wall(self, j, tau, alpha, stat)
        if (stat /= VCI_OK) then
          if (.not. self%sys%unrecoverable) stat = VCI_OK
          return
        end if
      end if
      self%x_stage1(1:nx + 1) = self%x(1:nx + 1)
      s1res = self%last_residual
      call self%sys%get_endpoint(self%x_stage1, self%q_wall)
      ! the motion at this impulse must reach wall j first: a wall admissible at the start and
      ! violated at wall j's point was crossed on the way, unseen (the next sub-step would start
      ! beyond it and reflect there as if on it: seed 14739, 1.4e-2 beyond)
      call self%sys%eval_gaps(self%q_wall, self%gaps_trial(1:self%ng), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'gap evaluation at the wall'); return
      end if
      crossed = crossed_before(j)
      if (stat /= VCI_OK) return
      call self%sys%momentum_out(self%x_stage1, self%q_start, alpha * tau, self%p_arrive, stat, self%p_start)
      if (stat == VCI_OK) call self%sys%energy_out(self%x_stage1, self%q_start, alpha * tau, e_minus, stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'momentum at the wall'); return
      end if
      call tie_row(e_minus, mu, f, tol_unused)
      if (stat /= VCI_OK) return
      evaluate = ieee_is_finite(f)
      consistent = .true.; mu_state = mu
      ! a motion that crosses another wall first is a secant point, never the root (its sub-step
      ! does not end at wall j)
      if (evaluate .and. .not. crossed .and. abs(f) < abs(f_best)) then
        mu_best = mu; f_best = f
      end if
    end function evaluate

    !> Does the sub-step from q_start to the point on wall `reached` (its gaps in gaps_trial) end
    !> beyond another wall that it started on the admissible side of, or on (to round-off: imp's own
    !> wall, which it leaves) and now beyond by more than the solver's tolerance? (Reversal seed
    !> 35643: imp's wall read -1.4e-17 at the start, so a tied impulse whose motion went back
    !> through it, 7.6e-6 deep, before wall j was taken, and the impact point lay beyond it.)
    !> stat is set where a gradient fails (then true).
    logical function crossed_before(reached)
      integer, intent(in) :: reached
      integer :: k
      crossed_before = .false.
      do k = 1, self%ng
        if (k == reached .or. .not. self%gaps_trial(k) < 0.0_dp) cycle
        if (self%gaps_start(k) >= 0.0_dp) then
          crossed_before = .true.
        else
          call start_gradient(self, k, stat)
          crossed_before = stat /= VCI_OK .or. &
                           self%gaps_trial(k) < -start_gap_tolerance(self, k, self%gaps_trial(k))
        end if
        if (crossed_before) return
      end do
    end function crossed_before
  end subroutine tie_to_wall

  !> Two solutions of a step with a soft impact (docs/BACKWARD.md, "Two solutions of a step with a
  !> soft impact"; issue 24). imp, an impact at q_start, took the root mu_w of its energy row
  !> (discrete or blended, m = 0) whose motion either leaves the rest tau of the step free (the
  !> step's last impact: wall_taken = 0) or meets wall wall_taken within it (tied there by
  !> tie_to_wall). Another impulse on the reflection's side may give the other kind of motion and
  !> meet the row too: for a root that leaves free, one whose motion meets a wall (any wall) within
  !> the rest, the row held on the sub-step up to that wall; for a tied root, one whose motion
  !> leaves the rest free, the row held on the whole rest. The step then has two solutions, and the
  !> other direction, which cuts the motion into other sub-steps, may take the other one (vci_fuzz
  !> --reversal 31255: backward 1.501 where the forward run took 1.136 and met a second impact).
  !> True when such a root is found; the caller counts an irreversible impact. The step is left as
  !> it was: x, the sub-step's points and momenta, its gaps, the wall normal, the carried position
  !> part (of q_start, or of the wall point after a tie, where the next sub-step starts), the
  !> scheme's row sizes (keep_row_sizes) and the posed sub-step are put back, and the search's
  !> failures are not the step's (a callback's unrecoverable failure is).
  !>
  !> On the impulse line mu = t mu_w the row is F(t), on the sub-step that really leaves imp at that
  !> impulse (up to the first wall its motion meets, else the whole rest; leaving_row); F(1) = 0.
  !> The window of impulses a root can have: at any root H+ - H- = -w delta (vci_scheme:
  !> blended_row), |delta| <= |e+| + |e-| with e the two sub-steps' offsets E_d - H (O(tau^2) for a
  !> symmetric scheme); with |e+| taken as at most about the taken root's (its sub-step, the whole
  !> rest, is the longest), |H+ - H-| <= D = OFFSET_MARGIN (|e+_w| + |e-|), and H is a parabola in t
  !> (through t = 0, 1/2, 1; exact for H quadratic in p): t_lo and t_hi on the reflection's side.
  !> Below 1 the motion comes back to the wall it leaves, above 1 it may reach another wall ahead
  !> (90992); each side is searched from its far end (side_has_root): one sub-step there decides
  !> whether the motion comes back at all (the screen), and only then is F looked at. OFFSET_MARGIN
  !> 2 and max_golden 4 were chosen by cost: 4 and 8 found the same 19 runs of the survey at 1.14
  !> times the instructions on seed 98668 (docs/bench/poke.md). Not on systems of reuse_min
  !> unknowns and more, where Newton keeps factors across solves, which the search's solves would
  !> change.
  logical function second_root_exists(self, imp, mu_w, tau, wall_taken, e_taken, stat) result(found)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: imp
    real(dp), intent(in) :: mu_w          !< the root taken, in the stepper's sign (p+ = p- + mu_w grad g)
    real(dp), intent(in) :: tau
    !> 0: the root taken leaves the rest free (the step's last impact); else it was tied to this
    !> wall, and e_taken is E_d of its sub-step up to it (resolve_impacts after tie_to_wall)
    integer, intent(in) :: wall_taken
    real(dp), intent(in) :: e_taken
    integer, intent(out) :: stat
    real(dp), parameter :: OFFSET_MARGIN = 2.0_dp
    real(dp), parameter :: GOLDEN = 0.6180339887498949_dp
    real(dp), parameter :: MAX_RATIO = 4.0_dp        ! (as energy_along: within a factor 4 of the root taken)
    integer, parameter :: max_golden = 4, max_refine = 40
    integer :: nx, st, wall_met
    real(dp) :: h0, hh, h1, e_w, d_off, b, c, t_f, t_lo, t_hi, disc, tol, gap_met
    logical :: want_return, screening
    found = .false.
    screening = .false.
    stat = VCI_OK
    nx = self%nsub
    if (.not. (self%has_energy .and. self%m == 0)) return
    if (imp%condition /= VCI_IMPACT_DISCRETE .and. imp%condition /= VCI_IMPACT_BLENDED) return
    if (nx + 1 >= self%newton%reuse_min) return
    if (.not. (abs(mu_w) > 0.0_dp)) return          ! a touch: no impulse, no reflection's side
    want_return = wall_taken == 0                    ! the other kind of root than the one taken
    ! the step as it stands (the next sub-step starts at q_start, or, after a tie, at q_wall)
    self%tie_x(1:nx + 1, 1) = self%x(1:nx + 1)
    self%tie_q(:, 1) = self%q_end; self%tie_q(:, 2) = self%q_wall; self%tie_q(:, 3) = self%p_arrive
    self%poke_keep_g(1:self%ng) = self%gaps_end(1:self%ng)
    if (want_return) then
      call self%sys%position_carry(self%q_start, self%poke_keep_q(:, 5))
    else
      call self%sys%position_carry(self%q_wall, self%poke_keep_q(:, 5))
    end if
    call self%sys%keep_row_sizes()     ! (the next solve's row sizes come from the last Jacobian)

    ! the window of impulses a root can have
    if (want_return) then
      call self%sys%energy_out(self%x, self%q_start, tau, e_w, stat)
    else
      e_w = e_taken
    end if
    if (stat == VCI_OK) call line_energy(0.0_dp, h0)
    if (stat == VCI_OK) call line_energy(0.5_dp * mu_w, hh)
    if (stat == VCI_OK) call line_energy(mu_w, h1)
    if (stat /= VCI_OK) goto 90
    d_off = OFFSET_MARGIN * (abs(e_w - h1) + abs(self%e_arrive_last - h0))
    c = 2.0_dp * (h1 - 2.0_dp * hh + h0)             ! H = h0 + b t + c t^2 along mu = t mu_w
    b = h1 - h0 - c
    if (.not. (c > 0.0_dp)) goto 90                  ! H not convex along the normal: not sought
    t_f = -b / (2.0_dp * c)
    if (.not. (t_f < 1.0_dp)) goto 90
    t_lo = t_f                                       ! H(t) = h0 - d_off on the reflection's side
    disc = b**2 - 4.0_dp * c * d_off
    if (disc > 0.0_dp) t_lo = (-b + sqrt(disc)) / (2.0_dp * c)
    t_lo = max(t_lo, t_f + 0.02_dp * (1.0_dp - t_f))
    t_hi = min((-b + sqrt(b**2 + 4.0_dp * c * d_off)) / (2.0_dp * c), MAX_RATIO)   ! H(t) = h0 + d_off
    if (.not. (t_lo < 0.99_dp .or. t_hi > 1.01_dp)) goto 90
    call self%sys%eval_gaps(self%q_start, self%gaps_start(1:self%ng), stat)
    if (stat /= VCI_OK) goto 90
    call forget_start_gradients(self)
    ! smaller impulses (the motion comes back to the wall it leaves, or to another), then larger
    ! ones (another wall ahead: 90992, where the forward's impulse is 1.09 times the backward's)
    if (t_lo < 0.99_dp) found = side_has_root(t_lo)
    if (.not. found .and. stat == VCI_OK .and. t_hi > 1.01_dp) found = side_has_root(t_hi)

    ! back to the step as it was
90  continue
    if (stat /= VCI_OK .and. .not. self%sys%unrecoverable) stat = VCI_OK
    if (stat == VCI_OK) self%cause = ''
    self%x(1:nx + 1) = self%tie_x(1:nx + 1, 1)
    self%q_end = self%tie_q(:, 1); self%q_wall = self%tie_q(:, 2); self%p_arrive = self%tie_q(:, 3)
    self%p_start = imp%p_after
    self%gaps_end(1:self%ng) = self%poke_keep_g(1:self%ng)
    call self%sys%set_wall_normal(imp%grad_g)
    if (want_return) then
      call self%sys%restore_position_carry(self%q_start, self%poke_keep_q(:, 5))
    else
      call self%sys%restore_position_carry(self%q_wall, self%poke_keep_q(:, 5))
    end if
    call self%sys%restore_row_sizes()
    call forget_start_gradients(self)
    ! x holds increments from the posed start: the leaving sub-step posed again (as find_poke leaves it)
    call self%sys%pose_substep(self%q_start, self%p_start, tau, st)
    if (st /= VCI_OK .and. stat == VCI_OK) then
      stat = st; call set_cause(self, 'constraint forms')
    end if
    if (stat /= VCI_OK) found = .false.
  contains
    !> H(q, p- + mu grad g) at the impact
    subroutine line_energy(mu, e)
      real(dp), intent(in) :: mu
      real(dp), intent(out) :: e
      self%p_leave = imp%p_before + mu * imp%grad_g
      call self%sys%hamiltonian(imp%q, self%p_leave, e, stat)
    end subroutine line_energy

    !> Is there a root of F of the other kind (want_return: its motion meets a wall; else it leaves
    !> the rest free) between t = 1 and t_far (t_lo or t_hi)? The screen: the motion at t_far must be
    !> of that kind (else none between, the end gap being monotone in the impulse), decided by its
    !> sub-step alone. Then t_g, where the kind changes (by the end gap of the wall met at t_far, or
    !> tied to, about linear in t: interpolation between t_far and 1, again from a probe that
    !> overshot), and F just inside the graze, at t_g + 1e-3 (t_far - t_g): in 91440 (backward, at
    !> t = 1.6403) F is above 0 only between the root, t = 0.9741, and the graze, 0.9754, 6e-3 of
    !> [t_lo, 1] (a scan of 41 impulses). Where F there and at t_far have one sign, F may still
    !> cross 0 and back in between (98668: F rises to the blended weight's kink and falls, above 0
    !> for t in 0.615-0.640 of [0.40, 1]; 90992, above 1: the other way round): golden sections
    !> for its extremum of the other sign, up to max_golden, stopping at the first value of that
    !> sign. Illinois steps then close the bracket to the row's tolerance; the root counts where
    !> its motion is of that kind.
    logical function side_has_root(t_far) result(has)
      real(dp), intent(in) :: t_far
      real(dp) :: f_far, g_far, t_g, t_p, f_p, t_a, f_a, t_b, f_b, t_c, f_c, t_d, f_d, t, f, w_a, w_b, sig
      integer :: k, kept, wall_back
      logical :: returns, ok
      has = .false.
      screening = .true.         ! (a motion of the kind taken: no stage 1, no row)
      ok = leaving_row(t_far * mu_w, f_far, returns)
      screening = .false.
      if (.not. ok .or. (returns .neqv. want_return)) return
      if (abs(f_far) <= tol) then
        has = .true.; return
      end if
      ! the wall whose end gap changes sign between t_far and 1: the one met at t_far, or the one
      ! the root taken was tied to
      if (want_return) then
        wall_back = wall_met; g_far = gap_met
      else
        wall_back = wall_taken; g_far = self%gaps_end(wall_taken)
      end if
      t_g = t_far + (1.0_dp - t_far) * g_far / (g_far - self%poke_keep_g(wall_back))
      if (.not. ((t_g - t_far) * (1.0_dp - t_g) > 0.0_dp)) return
      do k = 1, 3
        t_p = t_g + 1.0e-3_dp * (t_far - t_g)
        if (.not. leaving_row(t_p * mu_w, f_p, returns)) return
        if (returns .eqv. want_return) exit
        t_g = t_far + (t_p - t_far) * g_far / (g_far - self%gaps_end(wall_back))
      end do
      if (returns .neqv. want_return) return
      if (abs(f_p) <= tol) then
        has = .true.; return
      end if
      if ((f_p > 0.0_dp) .eqv. (f_far > 0.0_dp)) then
        ! golden sections on [t_a, t_b] for the largest -sig F (sig: the sign at both ends)
        sig = sign(1.0_dp, f_far)
        t_a = min(t_far, t_p); t_b = max(t_far, t_p)
        t_c = t_b - GOLDEN * (t_b - t_a); t_d = t_a + GOLDEN * (t_b - t_a)
        if (.not. leaving_row(t_c * mu_w, f_c, returns)) return
        if (.not. leaving_row(t_d * mu_w, f_d, returns)) return
        do k = 1, max_golden
          if (sig * f_c < 0.0_dp .or. sig * f_d < 0.0_dp) exit
          if (sig * f_c < sig * f_d) then
            t_b = t_d; t_d = t_c; f_d = f_c
            t_c = t_b - GOLDEN * (t_b - t_a)
            if (.not. leaving_row(t_c * mu_w, f_c, returns)) return
          else
            t_a = t_c; t_c = t_d; f_c = f_d
            t_d = t_a + GOLDEN * (t_b - t_a)
            if (.not. leaving_row(t_d * mu_w, f_d, returns)) return
          end if
        end do
        if (sig * f_c < 0.0_dp) then
          t_p = t_c; f_p = f_c
        else if (sig * f_d < 0.0_dp) then
          t_p = t_d; f_p = f_d
        else
          return
        end if
      end if
      ! Illinois steps on the bracket [t_far, t_p] (F of opposite signs) to the row's tolerance
      t_a = t_far; f_a = f_far; t_b = t_p; f_b = f_p
      w_a = f_a; w_b = f_b; kept = 0
      do k = 1, max_refine
        t = t_a - w_a * (t_b - t_a) / (w_b - w_a)
        if (.not. leaving_row(t * mu_w, f, returns)) return
        if (abs(f) <= tol) then
          has = returns .eqv. want_return; return
        end if
        if (abs(t_b - t_a) <= 8.0_dp * epsilon(1.0_dp) * abs(t)) return
        call illinois_update(t, f, t_a, f_a, w_a, t_b, f_b, w_b, kept)
      end do
    end function side_has_root

    !> F at impulse mu: imp's row (blended_row: the discrete one where its weight is 1) with E_d of
    !> the sub-step that leaves imp at mu, up to the first wall its motion reaches (returns) or over
    !> the whole rest; tol the row's tolerance. False where a solve fails or the motion crosses
    !> another wall before the one stage 1 reached (that sub-step is not the one that leaves).
    logical function leaving_row(mu, f, returns)
      real(dp), intent(in) :: mu
      real(dp), intent(out) :: f
      logical, intent(out) :: returns
      real(dp) :: e_out, alpha, sc
      integer :: j, jw
      leaving_row = .false.; returns = .false.; f = huge(1.0_dp)
      self%p_start = imp%p_before + mu * imp%grad_g
      call self%sys%put_endpoint(self%x, self%q_start, self%tie_q(:, 1))
      call substep(self, self%q_start, self%p_start, tau, stat)
      if (stat /= VCI_OK) return
      call self%sys%get_endpoint(self%x, self%q_end)
      call self%sys%eval_gaps(self%q_end, self%gaps_end(1:self%ng), stat)
      if (stat /= VCI_OK) return
      self%wall_tried(1:self%ng) = .false.
      jw = first_by_chord(self, self%gaps_end)
      wall_met = jw
      if (jw > 0) gap_met = self%gaps_end(jw)
      if (screening .and. ((jw > 0) .neqv. want_return)) then
        returns = jw > 0; return
      end if
      if (jw == 0) then
        call self%sys%energy_out(self%x, self%q_start, tau, e_out, stat)
      else
        returns = .true.
        alpha = -1.0_dp
        if (jw == imp%gap) call back_to_the_wall_left(mu, alpha)
        if (stat /= VCI_OK) return
        if (alpha < 0.0_dp) call stage_wall(self, jw, tau, alpha, stat)
        if (stat /= VCI_OK) return
        call self%sys%get_endpoint(self%x, self%q_wall)
        call self%sys%eval_gaps(self%q_wall, self%gaps_trial(1:self%ng), stat)
        if (stat /= VCI_OK) return
        do j = 1, self%ng
          if (j /= jw .and. self%gaps_start(j) >= 0.0_dp .and. self%gaps_trial(j) < 0.0_dp) return
        end do
        call self%sys%energy_out(self%x, self%q_start, alpha * tau, e_out, stat)
      end if
      if (stat /= VCI_OK) return
      call self%sys%set_wall_normal(imp%grad_g)
      call self%sys%pose_stage2(imp%q, imp%p_before, tau, imp%gap, self%e_arrive_last)
      call self%sys%pose_blend(stat)
      if (stat == VCI_OK) call self%sys%blended_row(e_out, mu, f, sc, stat)
      if (stat /= VCI_OK) return
      tol = self%settings%atol + self%settings%rtol * sc
      leaving_row = ieee_is_finite(f)
    end function leaving_row

    !> Stage 1 back to the wall imp left, from a start on it (x: the sub-step over tau at mu, its
    !> end beyond that wall): the chord from a point on the wall crosses it at once, so stage_wall's
    !> chord start fails there and it brackets the crossing on the trajectory (about 7 sub-steps:
    !> 90 % of the search's cost on seed 98668). The gap along the trajectory is about
    !> r s + (g_end - r) s^2 with r the departure's normal rate times tau: Newton on stage 1 from the
    !> sub-step of s tau at its root s. alpha < 0 where that fails or reaches the start itself
    !> (the caller then takes stage_wall's way); the sub-step's solution in x is then lost.
    subroutine back_to_the_wall_left(mu, alpha)
      real(dp), intent(in) :: mu
      real(dp), intent(out) :: alpha
      real(dp) :: rate, noise, r, s_est
      integer :: j
      alpha = -1.0_dp
      j = imp%gap
      self%q_wall = imp%q; self%p_arrive = imp%p_before
      call self%sys%set_wall_normal(imp%grad_g)
      call normal_rate(self, mu, rate, noise, stat)
      if (stat /= VCI_OK) return
      r = rate * tau
      if (.not. (r > 0.0_dp .and. self%gaps_end(j) < 0.0_dp)) return
      s_est = r / (r - self%gaps_end(j))
      call start_gradient(self, j, stat)
      if (stat /= VCI_OK) return
      self%q_guess = self%q_start + s_est * (self%q_end - self%q_start)
      call self%sys%put_endpoint(self%x, self%q_start, self%q_guess)
      call substep(self, self%q_start, self%p_start, s_est * tau, stat)
      if (stat /= VCI_OK) then
        if (.not. self%sys%unrecoverable) stat = VCI_OK
        call self%sys%put_endpoint(self%x, self%q_start, self%q_end)   ! (stage_wall's start again)
        return
      end if
      call solve_wall(self, j, tau, s_est, 'stage 1 (back to the wall left)', stat)
      if (stat == VCI_OK) alpha = self%sys%get_extra(self%x, KIND_STAGE1)
      if (stat /= VCI_OK .or. .not. (alpha > 0.25_dp * s_est .and. alpha <= 1.0_dp)) then
        if (stat /= VCI_OK .and. .not. self%sys%unrecoverable) stat = VCI_OK
        alpha = -1.0_dp
        call self%sys%put_endpoint(self%x, self%q_start, self%q_end)
      end if
    end subroutine back_to_the_wall_left
  end function second_root_exists

  !> Does the sub-step from (q_start, p_start) of length tau (its solution in x) pass a wall and come
  !> back before it reaches a wall its end is beyond? Its end alone cannot tell: a curved motion
  !> near a graze crosses a wall and returns within one sub-step, and in a step with impacts the
  !> two directions cut the motion into different sub-steps, so one saw the crossing at a sub-step's
  !> end and the other did not (docs/BACKWARD.md). Samples the discrete trajectory (regular
  !> sub-steps of length s tau, s = 1/8 .. 7/8, each solve started between the last sample and the
  !> whole sub-step) up to the first with a negative gap, and where none is negative, at the least
  !> of a parabola through the least sample and its neighbours (refine_samples): poked is the wall
  !> crossed first there (only that wall counts when only > 0), bracketed on [lo, hi] with g(lo) =
  !> glo >= 0 > g(hi) = ghi and the two points' solutions in x_low, x_high. poked = 0: no poke (no
  !> negative sample, or a wall the end is beyond is crossed by then: stage 1 as before; or a
  !> sample's solve failed). A stage point beyond a wall where the samples cannot be used fails
  !> with VCI_ERR_IMPACT (unresolved_crossing). x and the caller's posed sub-step are left as they
  !> came.
  subroutine find_poke(self, tau, only, poked, lo, hi, glo, ghi, stat, cleared)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: tau
    integer, intent(in) :: only
    integer, intent(out) :: poked
    real(dp), intent(out) :: lo, hi, glo, ghi
    integer, intent(out) :: stat
    !> the screen cleared the sub-step with room to spare: the stage polynomial's (the same curve
    !> both ways), or the parabola's with its bend widened to POKE_FAR_BEND
    logical, intent(out), optional :: cleared
    real(dp) :: s
    integer :: nm, k, ihi
    logical :: screened, stage_path
    nm = self%nsub
    associate (g_prev => self%poke_gaps(1:self%ng, 1), lam => self%poke_lambda)
    poked = 0; lo = 0.0_dp; hi = 1.0_dp; glo = 0.0_dp; ghi = 0.0_dp; screened = .false.
    if (present(cleared)) cleared = .false.
    self%x_full(1:nm) = self%x(1:nm)
    call self%sys%eval_gaps(self%q_start, g_prev, stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap evaluation at the start of the sub-step'); return
    end if
    ! a scheme with interior stages screens on their polynomial: no solve unless it comes near a wall
    stage_path = screens_on_stages(self)
    if (stage_path) then
      screened = stage_screen(self, only, stat)
      if (present(cleared)) cleared = stat == VCI_OK .and. .not. screened
      if (stat /= VCI_OK .or. .not. screened) return
    end if
    call self%sys%get_multipliers(self%x_full, lam)
    call self%sys%put_endpoint(self%x_low, self%q_start, self%q_start)      ! (the start: a sub-step of length 0)
    call self%sys%put_multipliers(self%x_low, lam)
    self%poke_npath = 0
    call add_path_point(self, 0.0_dp, self%q_start, g_prev, self%x_low)
    call add_path_point(self, 1.0_dp, self%q_end, self%gaps_end(1:self%ng), self%x_full)
    ! The screen (schemes without a stage polynomial): one solve at s = 1/2 and the parabola through
    ! the start, that point and the end, its bend doubled for a margin, at s = 1/8 .. 7/8 (gap
    ! evaluations). Only where it comes below a wall that the end is not beyond is the trajectory
    ! sampled (most impacts: one solve here). With a stage polynomial the half sub-step is solved
    ! only once that screen has passed: samples_are_path starts from it.
    if (.not. path_sample(self, 0.5_dp, tau, stat)) then
      call restore_substep(self, tau, stat); return
    end if
    if (.not. stage_path) then
      screened = parabola_dips(self, only, POKE_BEND)
      if (present(cleared) .and. .not. screened) cleared = .not. parabola_dips(self, only, POKE_FAR_BEND)
    end if
    if (screened) then
      if (.not. samples_are_path(self, self%q_start, self%p_start, self%q_end, self%x_full, tau, lam, stat)) then
        ! (only > 0: tie_to_wall's trial impulses, where a sub-step that cannot tell is no failure)
        if (stat == VCI_OK .and. stage_path .and. only == 0) call unresolved_crossing(self, stat)
        screened = .false.
      end if
    end if
    if (stat /= VCI_OK .or. .not. screened) then
      call restore_substep(self, tau, stat); return
    end if
    ihi = 0
    do k = 1, POKE_SAMPLES
      s = real(k, dp) / real(POKE_SAMPLES + 1, dp)
      if (s /= 0.5_dp) then
        if (.not. path_sample(self, s, tau, stat)) exit
      end if
      ihi = poked_point(self, s, only)
      if (ihi /= 0) exit
    end do
    if (stat == VCI_OK .and. ihi == 0 .and. k > POKE_SAMPLES) call refine_samples(self, tau, only, ihi, stat)
    if (stat == VCI_OK .and. ihi > 0) call poke_bracket(self, ihi, only, poked, lo, hi, glo, ghi)
    call restore_substep(self, tau, stat)
    end associate
  end subroutine find_poke

  !> find_poke screened a whole step (no impact yet, both ends admissible) from its start and found
  !> no poke: would the other direction find one? It starts this same sub-step at its end (the
  !> step's end state) and samples regular sub-steps from there, a family that differs from the
  !> start's by the order-2 scheme's O(tau^3), so a graze shallower than that is poked one way only
  !> (C reversal seed 4984, Lobatto s = 1: wall 1's gap +5.8e-4 at the half sub-step from the
  !> start, -4.4e-4 at the half sub-step back from the end; the backward run reflected in a step
  !> the forward run took free). This direction cannot take that impact (stage 1 from the start
  !> finds no crossing: its discrete flow has none), and the other cannot be kept from it (a rule
  !> that drops pokes seen from one end only loses the pokes that retrace a soft impact of this
  !> direction: docs/DESIGN.md, "A poke seen from the end only"), so it is reported: true when
  !> find_poke, run again on the sub-step from (q_end, p_end) the other way over tau (exactly the
  !> other direction's computation), finds a poke, or fails the step there (a stage point beyond a
  !> wall in a sub-step that does not resolve the motion); the caller counts an irreversible
  !> impact. False where the solve from the end fails. The caller's sub-step, x and gaps_end are as
  !> find_poke left them; only a callback's failure is a failure.
  logical function poke_seen_from_end(self, dir, tau, stat) result(seen)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: dir
    real(dp), intent(in) :: tau
    integer, intent(out) :: stat
    integer :: nm, st, poked_end
    real(dp) :: lo, hi, glo, ghi
    logical :: solved
    nm = self%nsub
    stat = VCI_OK
    seen = .false.
    associate (keep_x => self%poke_keep_x(:, 1), keep_q => self%poke_keep_q, lam => self%poke_lambda)
    ! the end's momentum, as the step hands it to the next one (take_step's regular step)
    call self%sys%momentum_out(self%x, self%q_start, tau, keep_q(:, 4), st, self%p_start)
    if (st /= VCI_OK) then
      if (self%sys%unrecoverable) stat = st
      return
    end if
    ! the start's carried low part (compensated positions): the sub-steps from the end replace it
    call self%sys%position_carry(self%q_start, keep_q(:, 5))
    keep_x(1:nm) = self%x(1:nm)
    keep_q(:, 1) = self%q_start; keep_q(:, 2) = self%p_start; keep_q(:, 3) = self%q_end
    self%poke_keep_g(1:self%ng) = self%gaps_end(1:self%ng)
    call self%sys%get_multipliers(self%x, lam)
    ! the same sub-step from the end, the other way (Newton from its known end, the start)
    call self%sys%set_direction(-dir)
    self%q_start = keep_q(:, 3); self%p_start = keep_q(:, 4)
    call self%sys%put_endpoint(self%x, self%q_start, keep_q(:, 1))
    call self%sys%put_multipliers(self%x, lam)
    call substep(self, self%q_start, self%p_start, tau, st)
    solved = st == VCI_OK
    if (.not. solved .and. self%sys%unrecoverable) stat = st
    if (solved) then
      call self%sys%get_endpoint(self%x, self%q_end)
      call self%sys%eval_gaps(self%q_end, self%gaps_end(1:self%ng), stat)
      if (stat /= VCI_OK) call set_cause(self, 'gap evaluation at the start of the step (poke screen from its end)')
    end if
    ! (a start on a wall, to round-off, may be just beyond it from the end: find_poke then leaves
    ! that wall to stage 1, as the other direction's would)
    poked_end = 0
    if (solved .and. stat == VCI_OK) call find_poke(self, tau, 0, poked_end, lo, hi, glo, ghi, stat)
    if (stat == VCI_ERR_IMPACT) then
      ! (unresolved_crossing: the other direction fails this step there and splits it, this one
      ! need not; a report, not a failure)
      stat = VCI_OK; self%cause = ''; poked_end = -1
    end if
    ! back to the step as the caller had it
    call self%sys%set_direction(dir)
    self%q_start = keep_q(:, 1); self%p_start = keep_q(:, 2); self%q_end = keep_q(:, 3)
    self%gaps_end(1:self%ng) = self%poke_keep_g(1:self%ng)
    self%x_full(1:nm) = keep_x(1:nm)
    call self%sys%restore_position_carry(self%q_start, keep_q(:, 5))
    call restore_substep(self, tau, stat)
    seen = stat == VCI_OK .and. poked_end /= 0
    end associate
  end function poke_seen_from_end

  !> x back to the caller's solution (x_full) and its sub-step from (q_start, p_start) over tau posed
  !> again: the unknowns are increments from the posed start, and the samples posed shorter ones.
  !> Without it (before issue 24's third round) the parabola screen returned with the half sub-step
  !> posed; Lobatto's end momentum then missed its "sub-step just solved" path (its length differed)
  !> and was summed from differenced stages, with no polynomial start kept for the next step (the
  !> walled pendulum with s = 1 moved by round-off, 4e-14, and its Newton iterations by up to 3 %). stat
  !> keeps an earlier failure.
  subroutine restore_substep(self, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: tau
    integer, intent(inout) :: stat
    integer :: st
    self%x(1:self%nsub) = self%x_full(1:self%nsub)
    call self%sys%pose_substep(self%q_start, self%p_start, tau, st)
    if (st /= VCI_OK .and. stat == VCI_OK) then
      stat = st; call set_cause(self, 'constraint forms')
    end if
  end subroutine restore_substep

  !> The regular sub-step of s tau from (q_start, p_start), its solve started from x: its end in
  !> q_trial and the gaps there in gaps_trial. False when the solve failed (stat set only where a
  !> callback said the failure is unrecoverable) or a gap evaluation did (stat set).
  logical function gaps_inside(self, s, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: s, tau
    integer, intent(inout) :: stat
    integer :: st
    gaps_inside = .false.
    call substep(self, self%q_start, self%p_start, s * tau, st)
    if (st /= VCI_OK) then
      if (self%sys%unrecoverable) stat = st
      return
    end if
    call self%sys%get_endpoint(self%x, self%q_trial)
    call self%sys%eval_gaps(self%q_trial, self%gaps_trial(1:self%ng), stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap evaluation inside the sub-step'); return
    end if
    gaps_inside = .true.
  end function gaps_inside

  !> The trajectory's point at fraction s of the sub-step of length tau: the end of a regular
  !> sub-step of s tau from (q_start, p_start), its solve started between the nearest path points
  !> on either side, and its gaps; it joins the path (add_path_point). False when the solve failed
  !> (stat set when a callback said so) or a gap evaluation did. x holds the solution.
  logical function path_sample(self, s, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: s, tau
    integer, intent(out) :: stat
    integer :: i
    real(dp) :: f
    stat = VCI_OK
    path_sample = .false.
    i = 2
    do while (i < self%poke_npath .and. self%poke_path_s(i) < s)
      i = i + 1
    end do
    f = (s - self%poke_path_s(i - 1)) / (self%poke_path_s(i) - self%poke_path_s(i - 1))
    self%x(1:self%nsub) = (1.0_dp - f) * self%poke_path_x(1:self%nsub, i - 1) + f * self%poke_path_x(1:self%nsub, i)
    if (.not. gaps_inside(self, s, tau, stat)) return   ! (no sample, no poke)
    call add_path_point(self, s, self%q_trial, self%gaps_trial(1:self%ng), self%x)
    path_sample = .true.
  end function path_sample

  !> Insert the point at s (position q, gaps g, the solution x of the sub-step to it) into
  !> find_poke's path, kept sorted by s.
  subroutine add_path_point(self, s, q, g, x)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: s, q(:), g(:), x(:)
    integer :: i, np, nm
    nm = self%nsub
    np = self%poke_npath + 1
    i = np
    do while (i > 1)
      if (self%poke_path_s(i - 1) <= s) exit
      i = i - 1
    end do
    self%poke_path_s(i + 1:np) = self%poke_path_s(i:np - 1)
    self%poke_path_q(:, i + 1:np) = self%poke_path_q(:, i:np - 1)
    self%poke_path_g(1:self%ng, i + 1:np) = self%poke_path_g(1:self%ng, i:np - 1)
    self%poke_path_x(1:nm, i + 1:np) = self%poke_path_x(1:nm, i:np - 1)
    self%poke_path_s(i) = s; self%poke_path_q(:, i) = q; self%poke_path_g(1:self%ng, i) = g
    self%poke_path_x(1:nm, i) = x(1:nm)
    self%poke_npath = np
  end subroutine add_path_point

  !> The parabola screen (find_poke): does the parabola through the start, the half-way point and
  !> the end, its bend times `bend`, come below a wall the end is not beyond (only that wall when
  !> only > 0) at s = 1/8 .. 7/8? (A gap evaluation that fails: true, the samples decide.)
  logical function parabola_dips(self, only, bend)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: only
    real(dp), intent(in) :: bend     !< the parabola's bend times this (POKE_BEND: doubled)
    integer :: k, jj, st
    real(dp) :: s
    parabola_dips = .true.
    self%q_guess = self%poke_path_q(:, 2) - 0.5_dp * (self%q_start + self%q_end)   ! the bend at s = 1/2
    do k = 1, POKE_SAMPLES
      s = real(k, dp) / real(POKE_SAMPLES + 1, dp)
      self%q_trial = self%q_start + s * (self%q_end - self%q_start) + 4.0_dp * bend * s * (1.0_dp - s) * self%q_guess
      call self%sys%eval_gaps(self%q_trial, self%gaps_trial(1:self%ng), st)
      if (st /= VCI_OK) return
      do jj = 1, self%ng
        if (self%gaps_trial(jj) < 0.0_dp .and. self%gaps_end(jj) >= 0.0_dp .and. (only == 0 .or. jj == only)) return
      end do
    end do
    parabola_dips = .false.
  end function parabola_dips

  !> The path's point at s if it is beyond a wall the end is not beyond (only that wall when
  !> only > 0): its index; -1 when it is beyond a wall the end is beyond (then that wall is stage
  !> 1's, as without samples), or beyond another wall than only: no poke; 0 when beyond none.
  integer function poked_point(self, s, only)
    type(vci_stepper_t), intent(in) :: self
    real(dp), intent(in) :: s
    integer, intent(in) :: only
    integer :: i
    poked_point = 0
    i = findloc(self%poke_path_s(1:self%poke_npath), s, 1)
    if (i == 0) return
    associate (g => self%poke_path_g(1:self%ng, i))
      if (.not. any(g < 0.0_dp)) return
      poked_point = i
      if (any(g < 0.0_dp .and. self%gaps_end(1:self%ng) < 0.0_dp)) poked_point = -1
      if (only > 0) then
        if (.not. g(only) < 0.0_dp) poked_point = -1
      end if
    end associate
  end function poked_point

  !> No sample is beyond a wall, but a dip narrower than their spacing passes between them (issue 24:
  !> reversal seed 9830, midpoint, met a graze 1e-5 deep forward, where a sample fell in it, and
  !> not backward, where it lay between the samples at 1/4 and 3/8 of its sub-step). The gap
  !> along the trajectory is smooth, so a parabola through a wall's least interior sample and its
  !> neighbours tells where and how deep it is; while one comes below a wall the end is not beyond,
  !> the trajectory is sampled at its least, up to POKE_REFINEMENTS times (each refit with the new
  !> point). ihi: the new point's index when it is beyond such a wall, else 0.
  subroutine refine_samples(self, tau, only, ihi, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: tau
    integer, intent(in) :: only
    integer, intent(out) :: ihi, stat
    integer :: r, jj
    real(dp) :: s_least, g_least, s_fit, g_fit
    stat = VCI_OK
    ihi = 0
    do r = 1, POKE_REFINEMENTS
      g_least = 0.0_dp; s_least = -1.0_dp
      do jj = 1, self%ng
        if (self%gaps_end(jj) < 0.0_dp .or. (only > 0 .and. jj /= only)) cycle
        call fitted_least(self%poke_path_s(1:self%poke_npath), self%poke_path_g(jj, 1:self%poke_npath), s_fit, g_fit)
        if (g_fit < g_least) then
          g_least = g_fit; s_least = s_fit
        end if
      end do
      if (s_least < 0.0_dp) return
      if (.not. path_sample(self, s_least, tau, stat)) return
      ihi = max(poked_point(self, s_least, only), 0)
      if (ihi > 0) return
    end do
  end subroutine refine_samples

  !> The least of the parabola through the least interior value of g at the points s (sorted,
  !> distinct) and its neighbours: its place s_fit, kept inside the neighbours' interval by 5 % of
  !> it, and its value g_fit there; g_fit = huge where that parabola is not convex (then the least
  !> point is the least there).
  pure subroutine fitted_least(s, g, s_fit, g_fit)
    real(dp), intent(in) :: s(:), g(:)
    real(dp), intent(out) :: s_fit, g_fit
    integer :: i
    real(dp) :: d1, d2, c2
    s_fit = -1.0_dp; g_fit = huge(1.0_dp)
    if (size(s) < 3) return
    i = minloc(g(2:size(s) - 1), 1) + 1
    d1 = (g(i) - g(i - 1)) / (s(i) - s(i - 1)); d2 = (g(i + 1) - g(i)) / (s(i + 1) - s(i))
    c2 = (d2 - d1) / (s(i + 1) - s(i - 1))
    if (.not. c2 > 0.0_dp) return
    s_fit = 0.5_dp * (s(i - 1) + s(i)) - d1 / (2.0_dp * c2)       ! where d1 + c2 (2 s - s(i-1) - s(i)) = 0
    s_fit = min(max(s_fit, s(i - 1) + 0.05_dp * (s(i + 1) - s(i - 1))), s(i + 1) - 0.05_dp * (s(i + 1) - s(i - 1)))
    g_fit = g(i - 1) + (s_fit - s(i - 1)) * (d1 + c2 * (s_fit - s(i)))
  end subroutine fitted_least

  !> The bracket of find_poke's poke at the path's point ihi: the wall crossed first from the point
  !> before it (the least fraction of the way by its gaps; only that wall when only > 0), lo, hi,
  !> glo = its gap there (>= 0), ghi, and the two points' solutions in x_low, x_high.
  subroutine poke_bracket(self, ihi, only, poked, lo, hi, glo, ghi)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: ihi, only
    integer, intent(inout) :: poked
    real(dp), intent(inout) :: lo, hi, glo, ghi
    integer :: jj, nm
    real(dp) :: f, best, g0
    nm = self%nsub
    best = huge(1.0_dp)
    do jj = 1, self%ng
      if (.not. self%poke_path_g(jj, ihi) < 0.0_dp .or. (only > 0 .and. jj /= only)) cycle
      g0 = max(self%poke_path_g(jj, ihi - 1), 0.0_dp)
      f = g0 / (g0 - self%poke_path_g(jj, ihi))
      if (f < best) then
        best = f; poked = jj
      end if
    end do
    if (poked == 0) return
    lo = self%poke_path_s(ihi - 1); hi = self%poke_path_s(ihi)
    glo = max(self%poke_path_g(poked, ihi - 1), 0.0_dp); ghi = self%poke_path_g(poked, ihi)
    self%x_low(1:nm) = self%poke_path_x(1:nm, ihi - 1)
    self%x_high(1:nm) = self%poke_path_x(1:nm, ihi)
  end subroutine poke_bracket

  !> The stage screen dipped but the sub-step does not resolve the motion (samples_are_path), so no
  !> sample can place a crossing: if one of its own stage points is beyond a wall its end is not
  !> beyond, the sub-step passes that wall and comes back, and ending the step there without an
  !> impact is wrong without a sign (the walled pendulum, Lobatto s = 3, h = 1: the step from t = 8
  !> has stage points 0.16 beyond wall 1, misses the impacts at 8.24 and 8.81 and ended the run 6.4
  !> off with status 0). Then VCI_ERR_IMPACT with the cause (the safety net splits the step); else
  !> stat as it came (only the bound's margin dipped: no poke, as before). A scheme without interior
  !> stages has no solved point inside to tell (its half sub-step is another solve, and failing on
  !> it sent a stiff spring at h omega >= 10 through the net's splits to |dH|/H = 3e6): it keeps
  !> the old behaviour. Called for resolve_impacts' own sub-steps only (not tie_to_wall's trials).
  subroutine unresolved_crossing(self, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(inout) :: stat
    integer :: j, d
    real(dp) :: g_least
    d = self%sys%path_degree()
    do j = 1, self%ng
      if (self%gaps_end(j) < 0.0_dp) cycle
      g_least = minval(self%poke_gaps(j, 4:2 + d))          ! (stage_screen's gaps at the stage points)
      if (g_least < 0.0_dp) then
        stat = VCI_ERR_IMPACT
        call vci_set_message(self%cause, trim(wall_label('poke screen (wall ', j))//': a stage point is '// &
          trim(vci_real_text(-g_least, '(es9.2)'))//' beyond the wall and the end is not, but the sub-step does not '// &
          'resolve the motion (two half sub-steps do not end where it does), so no sample can place the crossing; '// &
          'a shorter step can')
        return
      end if
    end do
  end subroutine unresolved_crossing

  !> The poke screen of a scheme with interior stages (issue 25; docs/DESIGN.md, "A wall poked within
  !> one sub-step"): the solved sub-step's positions are the polynomial of degree d = path_degree
  !> through its stage points, so the gap of each wall is evaluated at the d - 1 interior points (no
  !> solve) and the polynomial P through the gaps at all d + 1 points bounds it in between. The
  !> margin is the parabola screen's: P's departure from the chord of its end values doubled,
  !> M = 2 P - chord; the screen passes when M stays at or above min(0, g(start)) on [0, 1] (the
  !> start may lie on a wall, to round-off, after an impact), which the least Bernstein coefficient
  !> of M proves, refined by subdivision (bernstein_dips). Only walls the end is not beyond (and
  !> only that wall when only > 0) count. Gaps at the start in poke_gaps(:, 1), at the end in
  !> gaps_end; q_trial and gaps_trial are scratch.
  logical function stage_screen(self, only, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: only
    integer, intent(out) :: stat
    real(dp) :: w(0:PATH_MAX_DEGREE, 0:PATH_MAX_DEGREE), b(0:PATH_MAX_DEGREE), c, g0, g1
    integer :: d, i, j, k
    stage_screen = .true.
    d = self%sys%path_degree()
    call self%sys%path_bernstein(w(0:d, 0:d))
    associate (gn => self%poke_gaps(1:self%ng, 3:3 + d))
      gn(:, 1) = self%poke_gaps(1:self%ng, 1)
      gn(:, d + 1) = self%gaps_end(1:self%ng)
      do i = 1, d - 1
        call self%sys%path_point(self%x, i, self%q_trial, c)
        call self%sys%eval_gaps(self%q_trial, gn(:, i + 1), stat)
        if (stat /= VCI_OK) then
          call set_cause(self, 'gap evaluation at a stage point'); return
        end if
      end do
      do j = 1, self%ng
        if (self%gaps_end(j) < 0.0_dp .or. (only > 0 .and. j /= only)) cycle
        g0 = gn(j, 1); g1 = gn(j, d + 1)
        do k = 0, d
          b(k) = 2.0_dp * dot_product(w(k, 0:d), gn(j, :)) - (g0 + real(k, dp) / real(d, dp) * (g1 - g0)) &
                 - min(0.0_dp, g0)
        end do
        b(0) = max(b(0), 0.0_dp); b(d) = max(b(d), 0.0_dp)   ! (M's end values, exactly, before round-off)
        if (bernstein_dips(b(0:d))) return
      end do
    end associate
    stage_screen = .false.
  end function stage_screen

  !> Does the poke screen read the scheme's stage polynomial (stage_screen) rather than the parabola
  !> through a half sub-step? Schemes with interior stages, up to the degree stage_screen takes.
  logical function screens_on_stages(self)
    type(vci_stepper_t), intent(inout) :: self
    integer :: d
    d = self%sys%path_degree()
    screens_on_stages = d >= 2 .and. d <= PATH_MAX_DEGREE
  end function screens_on_stages

  !> Might the polynomial with Bernstein coefficients b(0:d) on [0, 1] be negative there? False when
  !> every coefficient of it, or of each piece after up to BERNSTEIN_SPLITS halvings (de Casteljau),
  !> is >= 0 (the convex hull property); true at a negative value (a piece's end) or when pieces are
  !> still undecided after the last halving.
  pure logical function bernstein_dips(b)
    real(dp), intent(in) :: b(0:)
    integer, parameter :: BERNSTEIN_SPLITS = 4
    real(dp) :: stack(0:PATH_MAX_DEGREE, 0:BERNSTEIN_SPLITS + 1), left(0:PATH_MAX_DEGREE), t(0:PATH_MAX_DEGREE)
    integer :: level(0:BERNSTEIN_SPLITS + 1), top, d, r, k, lv
    d = ubound(b, 1)
    bernstein_dips = .true.
    top = 0; stack(0:d, 0) = b; level(0) = 0
    do while (top >= 0)
      t(0:d) = stack(0:d, top); lv = level(top); top = top - 1
      if (t(0) < 0.0_dp .or. t(d) < 0.0_dp) return
      if (minval(t(0:d)) >= 0.0_dp) cycle
      if (lv == BERNSTEIN_SPLITS) return
      ! halve: left piece's coefficients are the first column of de Casteljau's triangle, the right's the last row
      left(0) = t(0)
      do r = 1, d
        do k = 0, d - r
          t(k) = 0.5_dp * (t(k) + t(k + 1))
        end do
        left(r) = t(0)
      end do
      top = top + 1; stack(0:d, top) = t(0:d); level(top) = lv + 1     ! right piece
      top = top + 1; stack(0:d, top) = left(0:d); level(top) = lv + 1  ! left piece (next)
    end do
    bernstein_dips = .false.
  end function bernstein_dips

  !> Are the ends of shorter sub-steps from (a, pa) a path between the ends a, b of the sub-step of
  !> length tau, solved in xw (find_poke's samples; poke_departure's short sub-step)? Only where
  !> the scheme resolves the motion: then the second half sub-step, from the end of the first
  !> (solved in x) with its momentum, ends where the whole sub-step does, in q and in p each to
  !> within POKE_PATH_FRACTION of the whole sub-step's change. A stiff spring at h omega = 10 is not
  !> resolved: the midpoint rule turns (q, p / omega) by 2 atan(5) in one sub-step and by 4 atan(2.5)
  !> in two halves; the departure test took its energy to 1e197 there (docs/BACKWARD.md). Both q
  !> and p: for a turn, one of the two misses is at least 1/sqrt(2) of sin(difference / 2) /
  !> sin(turn / 2) of its change, whatever the phase (q alone passed at h omega = 10). x is left as
  !> it came.
  logical function samples_are_path(self, a, pa, b, xw, tau, lam, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: a(:), pa(:), b(:), xw(:), tau, lam(:)
    integer, intent(out) :: stat
    integer :: nm, st
    real(dp) :: slack
    nm = self%nsub
    stat = VCI_OK
    samples_are_path = .false.
    associate (q_mid => self%poke_half(:, 1), p_mid => self%poke_half(:, 2), p_b => self%poke_half(:, 3), &
               p_two => self%poke_half(:, 4), a_lo => self%poke_half(:, 5))
      ! a's carried low part (compensated positions): the half sub-step from q_mid replaces it, and
      ! the caller's endpoint from a would then drop it (an ulp where the screen ran, none elsewhere)
      call self%sys%position_carry(a, a_lo)
      call self%sys%get_endpoint(self%x, q_mid)
      call self%sys%momentum_out(self%x, a, 0.5_dp * tau, p_mid, st, pa)
      if (st == VCI_OK) call self%sys%momentum_out(xw, a, tau, p_b, st, pa)
      if (st /= VCI_OK) then
        if (self%sys%unrecoverable) stat = st
        return
      end if
      self%x_high(1:nm) = self%x(1:nm)
      call self%sys%put_endpoint(self%x, q_mid, b)
      call self%sys%put_multipliers(self%x, lam)
      call substep(self, q_mid, p_mid, 0.5_dp * tau, st)
      if (st == VCI_OK) call self%sys%momentum_out(self%x, q_mid, 0.5_dp * tau, p_two, st, p_mid)
      if (st == VCI_OK) then
        call self%sys%get_endpoint(self%x, q_mid)
        slack = 10.0_dp * (self%settings%atol + self%settings%rtol * (norm2(b) + norm2(p_b)))
        samples_are_path = norm2(q_mid - b) <= POKE_PATH_FRACTION * norm2(b - a) + slack .and. &
                           norm2(p_two - p_b) <= POKE_PATH_FRACTION * norm2(p_b - pa) + slack
      else if (self%sys%unrecoverable) then
        stat = st
      end if
      call self%sys%restore_position_carry(a, a_lo)
    end associate
    self%x(1:nm) = self%x_high(1:nm)
    ! x holds increments from the posed start: pose the sub-step from a again, or the caller's x
    ! (xw, restored) reads as a motion from the half-way point (the walled pendulum at h = 1: a
    ! touch at 0.876 became an end at 1.223 beyond the wall, docs/BACKWARD.md)
    call self%sys%pose_substep(a, pa, tau, st)
    if (st /= VCI_OK) then
      stat = st; call set_cause(self, 'constraint forms')
    end if
  end function samples_are_path

  !> Might the whole step (no impact so far, its end admissible) pass a wall and come back? The
  !> screen before find_poke's solves, by gap evaluations only: the parabola through the previous
  !> step's start, this step's start a and its end b has its bend B = -(d - d_prev)/4 at s = 1/2
  !> (d, d_prev: this and the previous step's displacement); with the bend doubled for a margin, a
  !> linear g along it stays above min(g(a), g(b), g(c)) + min(0, g(c + 2B) - g(c)), c = (a + b)/2,
  !> and the step is sampled where that bound is negative. Without a previous regular step in this
  !> direction (the run's first step, after an impact or a reversal) find_poke's own screen decides.
  logical function may_poke(self, state, dir, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_state_t), intent(in) :: state
    integer, intent(in) :: dir
    real(dp), intent(in) :: tau
    integer, intent(out) :: stat
    integer :: j
    stat = VCI_OK
    may_poke = .true.
    if (state%predictor_depth * dir <= 0) return
    ! a stage polynomial screens at least as tightly, without the previous step (find_poke)
    if (screens_on_stages(self)) return
    ! (gaps_start and gaps_trial as scratch: an impact that follows evaluates them again)
    call self%sys%eval_gaps(self%q_start, self%gaps_start(1:self%ng), stat)
    self%q_trial = 0.5_dp * (self%q_start + self%q_end)
    if (stat == VCI_OK) call self%sys%eval_gaps(self%q_trial, self%poke_gaps(1:self%ng, 2), stat)
    ! c + 2B; the second difference d - d_prev = (q_end - q_start) - dir tau velocity
    self%q_trial = self%q_trial - 0.5_dp * ((self%q_end - self%q_start) - real(dir, dp) * tau * state%velocity)
    if (stat == VCI_OK) call self%sys%eval_gaps(self%q_trial, self%gaps_trial(1:self%ng), stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap evaluation inside the step'); return
    end if
    do j = 1, self%ng
      associate (gc => self%poke_gaps(j, 2))
        if (min(self%gaps_start(j), self%gaps_end(j), gc) + min(0.0_dp, self%gaps_trial(j) - gc) < 0.0_dp) return
      end associate
    end do
    may_poke = .false.
  end function may_poke

  !> Stage 1 for wall j, poked within the sub-step (find_poke's bracket [lo, hi] with the samples'
  !> solutions in x_low, x_high): Newton from the interpolated crossing. found when it reached the
  !> wall before hi (the first crossing). Where it went past hi (the way back out of the dip, though
  !> the motion enters the wall inside the bracket) or failed, the bracket is bisected on the
  !> trajectory and Newton started again, up to RESTARTS times; then, or where a sample's solve
  !> fails, or where Newton reached a fraction <= 0, found = .false. as before.
  subroutine stage_poke(self, j, tau, lo, hi, glo, ghi, alpha, found, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau, lo, hi, glo, ghi
    real(dp), intent(out) :: alpha
    logical, intent(out) :: found
    integer, intent(out) :: stat
    !> bisections of the bracket before each new start, and new starts, where Newton left it
    integer, parameter :: NARROWINGS = 2, RESTARTS = 4
    integer :: nm, st, k
    real(dp) :: a, b, ga, gb
    character(len=40) :: what
    found = .false.
    nm = self%nsub
    what = wall_label('stage 1 (reaching wall ', j)
    call start_gradient(self, j, stat)
    if (stat /= VCI_OK) return
    a = lo; b = hi; ga = glo; gb = ghi
    do k = 0, RESTARTS
      if (k > 0) then
        ! Newton went past the bracket, to where the motion comes back out of a dip (or failed),
        ! though the samples at its ends say the motion enters the wall inside it: narrow it on the
        ! samples and start again closer to the entry (reversal seed 26238, Lobatto s = 1:
        ! backward, the bracket [0.375, 0.5] of a dip 1.5e-5 deep led to the exit at 0.516 and the
        ! impact that the forward run met at the entry was dropped)
        if (.not. narrowed(NARROWINGS)) exit
      end if
      alpha = a + (b - a) * ga / max(ga - gb, tiny(1.0_dp))
      alpha = min(max(alpha, a + 1.0e-3_dp * (b - a)), b)
      self%x(1:nm) = self%x_low(1:nm) + (alpha - a) / (b - a) * (self%x_high(1:nm) - self%x_low(1:nm))
      call solve_wall(self, j, tau, alpha, what(1:len_trim(what)), st)
      if (st /= VCI_OK .and. self%sys%unrecoverable) then
        stat = st; return
      end if
      if (st == VCI_OK) then
        alpha = self%sys%get_extra(self%x, KIND_STAGE1)
        found = alpha > 0.0_dp .and. alpha <= hi
        if (found .or. .not. alpha > hi) return
      end if
    end do
    ! (the narrowing posed shorter sub-steps: the caller's own again, as restore_substep does)
    if (stat == VCI_OK) then
      call self%sys%pose_substep(self%q_start, self%p_start, tau, stat)
      if (stat /= VCI_OK) call set_cause(self, 'constraint forms')
    end if
  contains
    !> Bisect [a, b] count times on the discrete trajectory (regular sub-steps of length s tau, each
    !> started between the bracket's kept solutions), keeping g(a) >= 0 > g(b). False where a solve
    !> fails (stat set where a callback said so).
    logical function narrowed(count)
      integer, intent(in) :: count
      integer :: i
      real(dp) :: s, g
      narrowed = .false.
      do i = 1, count
        s = 0.5_dp * (a + b)
        self%x(1:nm) = 0.5_dp * (self%x_low(1:nm) + self%x_high(1:nm))
        if (.not. gaps_inside(self, s, tau, stat)) return
        g = self%gaps_trial(j)
        if (g < 0.0_dp) then
          b = s; gb = g; self%x_high(1:nm) = self%x(1:nm)
        else
          a = s; ga = g; self%x_low(1:nm) = self%x(1:nm)
        end if
      end do
      narrowed = .true.
    end function narrowed
  end subroutine stage_poke

  !> Stage 2's free motion over the rest tau2 (in x, its end in q_trial) ends off the wall (num >= 0),
  !> but it may depart into the wall and come back within tau2 (a wall poked within the sub-step, as
  !> find_poke meets it): then the impact needs an impulse all the same, and num becomes the change
  !> of g over tau2 at the departure's rate (a regular sub-step of 1e-3 tau2; the mirror start is
  !> then that of reflect_from_departure). A motion that departs off the wall keeps num (a touch:
  !> no impulse). x and the sub-step's kept factors are those of the free motion over tau2 again.
  subroutine poke_departure(self, tau2, num, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: tau2
    real(dp), intent(inout) :: num
    integer, intent(out) :: stat
    real(dp), parameter :: eps_frac = 1.0e-3_dp
    real(dp) :: rate
    integer :: nx, st
    logical :: resolved
    stat = VCI_OK
    nx = self%nsub
    self%x_saved(1:nx) = self%x(1:nx)
    self%q_guess = self%q_wall + eps_frac * (self%q_trial - self%q_wall)
    call self%sys%put_endpoint(self%x, self%q_wall, self%q_guess)
    call substep(self, self%q_wall, self%p_arrive, eps_frac * tau2, st)
    if (st /= VCI_OK) then
      self%x(1:nx) = self%x_saved(1:nx)
      if (self%sys%unrecoverable) then
        stat = st
      else
        call self%sys%pose_substep(self%q_wall, self%p_arrive, tau2, stat)
      end if
      return
    end if
    call self%sys%get_endpoint(self%x, self%q_guess)
    rate = dot_product(self%sys%grad, self%q_guess - self%q_wall) / eps_frac
    self%x(1:nx) = self%x_saved(1:nx)
    if (departs_off_wall(rate * eps_frac)) self%stats%irreversible_impacts = self%stats%irreversible_impacts + 1
    if (.not. rate < 0.0_dp) then
      call self%sys%pose_substep(self%q_wall, self%p_arrive, tau2, stat)   ! (the free motion's again)
      if (stat /= VCI_OK) call set_cause(self, 'constraint forms')
      return
    end if
    ! a departure into the wall and a free end off it are one motion only where the sub-step over
    ! tau2 resolves it (samples_are_path, from a half sub-step): a stiff spring turns by more than
    ! a right angle in one sub-step, and an impulse here took its energy to 1e197
    call self%sys%get_multipliers(self%x_saved, self%poke_lambda)
    call self%sys%put_endpoint(self%x, self%q_wall, 0.5_dp * (self%q_wall + self%q_trial))
    call substep(self, self%q_wall, self%p_arrive, 0.5_dp * tau2, st)
    resolved = .false.
    if (st == VCI_OK) then
      resolved = samples_are_path(self, self%q_wall, self%p_arrive, self%q_trial, self%x_saved, tau2, self%poke_lambda, stat)
    else if (self%sys%unrecoverable) then
      stat = st
    else
      call self%sys%pose_substep(self%q_wall, self%p_arrive, tau2, stat)
    end if
    self%x(1:nx) = self%x_saved(1:nx)
    if (stat /= VCI_OK .or. .not. resolved) return
    num = rate
    ! the free motion over tau2 once more (from its own solution: one iteration), for its factors
    call substep(self, self%q_wall, self%p_arrive, tau2, stat)
    if (stat /= VCI_OK) return
    call self%sys%get_endpoint(self%x, self%q_trial)
  contains
    !> A touch at a point stage 1 reached (the arriving positions cross into the wall there) whose
    !> momentum p- leaves the wall: the arriving positions and p- disagree on the side the motion
    !> comes from, an unresolved graze (their normal speeds differ by the scheme's O(tau^2)). The
    !> reversed motion arrives here with this same p- (a touch keeps it) and departs into the wall,
    !> so the other direction reflects where its stage 1 meets the point (reversal seed 101834,
    !> Lobatto s = 1: forward a touch, rate +1.9e-3 over a rest of 0.0123, backward an impulse of
    !> 0.286): counted (irreversible_impacts) where the departure dg, over 1e-3 of the rest, is off
    !> the wall by more than the solver's tolerance on g.
    logical function departs_off_wall(dg)
      real(dp), intent(in) :: dg
      real(dp) :: scale
      scale = sum(abs(self%sys%grad) * (abs(self%q_wall) + abs(self%q_guess - self%q_wall)))
      departs_off_wall = dg > 10.0_dp * (self%settings%atol + self%settings%rtol * scale)
    end function departs_off_wall
  end subroutine poke_departure

  !> Of the walls violated at the sub-step's end (gaps_end < 0), not yet tried and with gap(j) < 0,
  !> the one the chord q_start -> q_end crosses first (smallest g_start / (g_start - g_end)); 0: none.
  integer function first_by_chord(self, gap)
    type(vci_stepper_t), intent(in) :: self
    real(dp), intent(in) :: gap(:)
    integer :: k
    real(dp) :: f, best
    first_by_chord = 0
    best = huge(1.0_dp)
    do k = 1, self%ng
      if (self%wall_tried(k) .or. .not. (self%gaps_end(k) < 0.0_dp .and. gap(k) < 0.0_dp)) cycle
      f = max(self%gaps_start(k), 0.0_dp) / max(self%gaps_start(k) - self%gaps_end(k), tiny(1.0_dp))
      if (f < best .or. first_by_chord == 0) then
        best = f; first_by_chord = k
      end if
    end do
  end function first_by_chord

  !> grad_cache(:, grad_slot(j)) = wall j's gradient at q_start, unless a column already holds it
  !> (else the column after the last one written, whose wall loses it).
  subroutine start_gradient(self, j, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    integer, intent(out) :: stat
    integer :: k
    stat = VCI_OK
    if (self%grad_slot(j) > 0) return
    k = mod(self%last_slot, size(self%slot_wall)) + 1
    if (self%slot_wall(k) > 0) self%grad_slot(self%slot_wall(k)) = 0
    self%slot_wall(k) = 0
    call self%sys%eval_gap_gradient(self%q_start, j, self%grad_cache(:, k), stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap gradient at the start of the sub-step'); return
    end if
    self%slot_wall(k) = j; self%grad_slot(j) = k; self%last_slot = k
  end subroutine start_gradient

  !> A new q_start: no column holds a wall's gradient there (O(GRAD_SLOTS), not O(n_gaps)).
  subroutine forget_start_gradients(self)
    type(vci_stepper_t), intent(inout) :: self
    integer :: k
    do k = 1, size(self%slot_wall)
      if (self%slot_wall(k) > 0) self%grad_slot(self%slot_wall(k)) = 0
      self%slot_wall(k) = 0
    end do
  end subroutine forget_start_gradients

  !> Is configuration a (the sub-step's start) on wall j, to solver tolerance? (Not beyond it by
  !> more: refuse_start_beyond has refused such a start.)
  logical function on_wall(self, j)
    type(vci_stepper_t), intent(in) :: self
    integer, intent(in) :: j
    on_wall = self%gaps_start(j) <= start_gap_tolerance(self, j, self%gaps_start(j))
  end function on_wall

  !> The solver's tolerance on a value g of wall j's gap near the sub-step (wall j's gradient at
  !> its start in grad_cache): 10 (atol + rtol scale), scale the size of g's terms and of its
  !> change over the sub-step (as in stage 1's gap row).
  real(dp) function start_gap_tolerance(self, j, g)
    type(vci_stepper_t), intent(in) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: g
    real(dp) :: scale
    scale = abs(g) + sum(abs(self%grad_cache(:, self%grad_slot(j))) * (abs(self%q_start) + abs(self%q_end - self%q_start)))
    start_gap_tolerance = 10.0_dp * (self%settings%atol + self%settings%rtol * scale)
  end function start_gap_tolerance

  !> A sub-step must not start beyond a wall by more than the solver's tolerance (gaps_start; the
  !> wall just reflected from, last_gap, is on it by stage 1). The step's start is the end of an
  !> accepted step, where every gap was >= 0 (or the landed wall point, checked when landing); a
  !> later sub-step's start is the wall point of this step's last impact. So a step that starts
  !> beyond a wall met a gap callback that is not a function of q alone (it said >= 0 there before)
  !> or a model changed under the integrator: VCI_ERR_INADMISSIBLE, which a shorter step cannot
  !> cure. A wall point beyond another wall is stage 1's miss (the motion crossed that wall first,
  !> unseen): VCI_ERR_IMPACT, which the safety net retries with shorter steps. Taken as "on" the
  !> wall, either start reflected from inside it with status OK (fuzz_capi seeds 60, 131, 180, 473).
  subroutine refuse_start_beyond(self, last_gap, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: last_gap
    integer, intent(out) :: stat
    integer :: j
    stat = VCI_OK
    do j = 1, self%ng
      if (j == last_gap .or. .not. self%gaps_start(j) < 0.0_dp) cycle   ! (the rare case: a gradient)
      call start_gradient(self, j, stat)
      if (stat /= VCI_OK) return
      if (self%gaps_start(j) >= -start_gap_tolerance(self, j, self%gaps_start(j))) cycle
      if (last_gap == 0) then
        stat = VCI_ERR_INADMISSIBLE
        call vci_set_message(self%cause, vci_start_beyond_cause(j, self%gaps_start(j)))
      else
        stat = VCI_ERR_IMPACT
        call vci_set_message(self%cause, vci_crossed_unseen_cause(last_gap, '', j, self%gaps_start(j)))
      end if
      return
    end do
  end subroutine refuse_start_beyond

  !> An impact point on wall jstar (stage 1's, after any tie of the previous impact) must not lie
  !> beyond another wall, the one just reflected from included, by more than the solver's
  !> tolerance, or it is stage 1's miss: VCI_ERR_IMPACT (the safety net retries). Nothing else
  !> checks it: a step that lands there ends at that point, which the end-of-step test (every
  !> gap >= 0) never sees, and the sub-step reflected from it is checked at its start only when
  !> its end is beyond a wall (reversal seed 35643: a point 7.6e-6 beyond the wall just left was
  !> reflected from with status OK). One gap evaluation per impact.
  subroutine refuse_point_beyond(self, jstar, landing, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: jstar
    logical, intent(in) :: landing        !< the point ends the step (the message says so)
    integer, intent(out) :: stat
    integer :: k
    call self%sys%eval_gaps(self%q_wall, self%gaps_trial(1:self%ng), stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap evaluation at the wall'); return
    end if
    do k = 1, self%ng
      if (k == jstar .or. .not. self%gaps_trial(k) < 0.0_dp) cycle
      call start_gradient(self, k, stat)
      if (stat /= VCI_OK) return
      if (self%gaps_trial(k) >= -start_gap_tolerance(self, k, self%gaps_trial(k))) cycle
      stat = VCI_ERR_IMPACT
      if (landing) then
        call vci_set_message(self%cause, vci_crossed_unseen_cause(jstar, ' at the step''s end', k, self%gaps_trial(k)))
      else
        call vci_set_message(self%cause, vci_crossed_unseen_cause(jstar, '', k, self%gaps_trial(k)))
      end if
      return
    end do
  end subroutine refuse_point_beyond


  !> Stage 1 for wall j: find alpha in (0, 1], b on the wall, lambda. Initial guess from the chord a -> b.
  subroutine stage_wall(self, j, tau, alpha, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau
    real(dp), intent(out) :: alpha
    integer, intent(out) :: stat
    real(dp) :: lo, hi, glo, ghi
    character(len=40) :: what
    what = wall_label('stage 1 (reaching wall ', j)
    call start_gradient(self, j, stat)
    if (stat /= VCI_OK) return
    call self%sys%get_multipliers(self%x, self%lambda_start)
    ! Initial guess: the first crossing along the chord a -> b (g is cheap).
    call bracket_crossing(self, ALONG_CHORD, j, tau, lo, hi, glo, ghi, stat)
    if (stat /= VCI_OK) return
    alpha = max(hi, 1.0e-6_dp)
    self%q_guess = self%q_start + alpha * (self%q_end - self%q_start)
    call self%sys%put_endpoint(self%x, self%q_start, self%q_guess)
    call solve_wall(self, j, tau, alpha, what(1:len_trim(what)), stat)   ! (trim() would allocate)
    if (stat == VCI_OK) then
      alpha = self%sys%get_extra(self%x, KIND_STAGE1)
      if (alpha > 0.0_dp .and. alpha <= 1.0_dp) return
    else if (self%sys%unrecoverable) then
      return                                 ! a callback said so: no second start
    end if
    ! The chord is a poor guess when the sub-step is strongly curved (stiff forces, a second
    ! bounce in one step): bracket the crossing on the discrete trajectory itself, i.e. on the
    ! end points of regular sub-steps of length s tau, and start Newton inside that bracket.
    call trajectory_start(self, j, tau, alpha, stat)
    if (stat /= VCI_OK) return
    call solve_wall(self, j, tau, alpha, what(1:len_trim(what)), stat)
    if (stat /= VCI_OK) return
    alpha = self%sys%get_extra(self%x, KIND_STAGE1)
    if (.not. (alpha > 0.0_dp .and. alpha <= 1.0_dp)) then
      stat = VCI_ERR_IMPACT
      call vci_set_message(self%cause, trim(what)//': impact fraction '//trim(vci_real_text(alpha, '(es10.3)'))// &
        ' outside (0, 1]')
    end if
  end subroutine stage_wall

  !> Does the motion from (a, pa) depart into wall j? Sign of grad g_j . (b_eps - a) for the end
  !> b_eps of a regular sub-step of length 1e-3 tau. Leaves x, and the sub-step posed, as it found
  !> them.
  logical function departs_into(self, j, tau, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau
    integer, intent(out) :: stat
    real(dp), parameter :: eps_frac = 1.0e-3_dp
    integer :: nx, st
    nx = self%nsub
    self%x_saved(1:nx) = self%x(1:nx)
    self%q_guess = self%q_start + eps_frac * (self%q_end - self%q_start)
    call self%sys%put_endpoint(self%x, self%q_start, self%q_guess)
    call substep(self, self%q_start, self%p_start, eps_frac * tau, stat)
    call self%sys%get_endpoint(self%x, self%q_trial)
    departs_into = stat == VCI_OK .and. dot_product(self%grad_cache(:, self%grad_slot(j)), self%q_trial - self%q_start) < 0.0_dp
    self%x(1:nx) = self%x_saved(1:nx)
    ! the caller's sub-step posed again, as samples_are_path does: the same start, but a posed length
    ! of 1e-3 tau would be read by anything asking for the sub-step's own length (a Lobatto
    ! momentum_out compares it with its tau)
    call self%sys%pose_substep(self%q_start, self%p_start, tau, st)
    if (st /= VCI_OK .and. stat == VCI_OK) then
      stat = st; departs_into = .false.; call set_cause(self, 'constraint forms')
    end if
  end function departs_into

  !> Bracket the first crossing of wall j on s in [0, 1] (s = 1 is the end of the sub-step, known to
  !> be beyond the wall): samples at s = 1/8, ..., 7/8 up to the first negative gap, then Illinois
  !> steps (chord) or bisections (trajectory). Along the chord the point is q_start + s (q_end -
  !> q_start); along the trajectory it is the end of the regular sub-step of length s tau, and the
  !> sub-step solutions at the bracket's ends are kept in x_low and x_high. On return
  !> g_j(lo) = glo >= 0 > g_j(hi) = ghi (up to round-off at a start on the wall), or lo = hi where
  !> g_j is exactly 0.
  subroutine bracket_crossing(self, along, j, tau, lo, hi, glo, ghi, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: along, j
    real(dp), intent(in) :: tau
    real(dp), intent(out) :: lo, hi, glo, ghi
    integer, intent(out) :: stat
    integer, parameter :: samples = 7
    integer :: i, kept
    real(dp) :: s, g, wlo, whi
    lo = 0.0_dp; hi = 1.0_dp
    glo = self%gaps_start(j); ghi = self%gaps_end(j)
    stat = VCI_OK
    do i = 1, samples
      s = real(i, dp) / real(samples + 1, dp)
      call probe(s, g)
      if (stat /= VCI_OK) return
      if (g < 0.0_dp) exit
    end do
    if (along == ALONG_TRAJECTORY) then
      do i = 1, TRAJECTORY_BISECTIONS
        call probe(0.5_dp * (lo + hi), g)
        if (stat /= VCI_OK) return
      end do
      return
    end if
    ! Illinois: the secant of the bracket's (weighted) ends; an end kept twice in a row has its
    ! weight halved, so that both ends move in. Bisection where the secant point is not inside.
    wlo = max(glo, 0.0_dp); whi = ghi; kept = 0
    do i = 1, CHORD_REFINEMENTS
      if (hi - lo <= CHORD_WIDTH) exit
      s = lo + (hi - lo) * wlo / (wlo - whi)
      if (.not. (s > lo .and. s < hi)) s = 0.5_dp * (lo + hi)
      call probe(s, g)
      if (stat /= VCI_OK) return
      if (g == 0.0_dp) then         ! on the wall: both ends there
        hi = s; ghi = g; exit
      end if
      if (g < 0.0_dp) then          ! hi moved; lo kept
        whi = g
        if (kept < 0) wlo = 0.5_dp * wlo
        kept = -1
      else                          ! lo moved; hi kept
        wlo = g
        if (kept > 0) whi = 0.5_dp * whi
        kept = 1
      end if
    end do
  contains
    !> g_j at s; the bracket end it replaces moves to s.
    subroutine probe(s, g)
      real(dp), intent(in) :: s
      real(dp), intent(out) :: g
      integer :: nm
      nm = self%nsub
      if (along == ALONG_CHORD) then
        self%q_trial = self%q_start + s * (self%q_end - self%q_start)
      else
        ! Newton starts from the interpolation between the bracket's ends
        self%x(1:nm) = self%x_low(1:nm) + (s - lo) / (hi - lo) * (self%x_high(1:nm) - self%x_low(1:nm))
        call substep(self, self%q_start, self%p_start, s * tau, stat)
        if (stat /= VCI_OK) return
        call self%sys%get_endpoint(self%x, self%q_trial)
      end if
      call self%sys%eval_gaps(self%q_trial, self%gaps_trial(1:self%ng), stat)
      if (stat /= VCI_OK) then
        call set_cause(self, 'gap evaluation'); return
      end if
      g = self%gaps_trial(j)
      if (g < 0.0_dp) then
        hi = s; ghi = g
        if (along == ALONG_TRAJECTORY) self%x_high(1:nm) = self%x(1:nm)
      else
        lo = s; glo = g
        if (along == ALONG_TRAJECTORY) self%x_low(1:nm) = self%x(1:nm)
      end if
    end subroutine probe
  end subroutine bracket_crossing

  !> Stage 1's start when the chord fails: the crossing bracketed on regular sub-steps of length
  !> s tau, then linear interpolation of g_j; leaves the interpolated (b, lambda) in x and alpha.
  subroutine trajectory_start(self, j, tau, alpha, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau
    real(dp), intent(out) :: alpha
    integer, intent(out) :: stat
    integer :: nm
    real(dp) :: lo, hi, glo, ghi
    nm = self%nsub
    call self%sys%put_endpoint(self%x_low, self%q_start, self%q_start)
    call self%sys%put_multipliers(self%x_low, self%lambda_start)
    call self%sys%put_endpoint(self%x_high, self%q_start, self%q_end)
    call self%sys%put_multipliers(self%x_high, self%lambda_start)
    call bracket_crossing(self, ALONG_TRAJECTORY, j, tau, lo, hi, glo, ghi, stat)
    if (stat /= VCI_OK) return
    glo = max(glo, 0.0_dp)                ! a start on the wall may be below it by round-off
    alpha = lo + (hi - lo) * glo / max(glo - ghi, tiny(1.0_dp))
    alpha = min(max(alpha, lo + 1.0e-3_dp * (hi - lo)), hi)
    self%x(1:nm) = self%x_low(1:nm) + (alpha - lo) / (hi - lo) * (self%x_high(1:nm) - self%x_low(1:nm))
  end subroutine trajectory_start

  !> Newton on stage 1 from x(1:n) (and lambda in lam0) with alpha.
  subroutine solve_wall(self, j, tau, alpha, what, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau, alpha
    character(len=*), intent(in) :: what
    integer, intent(out) :: stat
    call self%sys%put_extra(self%x, KIND_STAGE1, alpha)
    call self%sys%pose_stage1(self%q_start, self%p_start, tau, j, self%grad_cache(:, self%grad_slot(j)), stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'constraint forms'); return
    end if
    call run_newton(self, self%sys%unknowns(KIND_STAGE1), what, stat)
  end subroutine solve_wall

  !> Stage 2 on wall j from (qt, p_minus) over tau2: q_next, lambda, impulse mu. Newton starts from
  !> the linearised reflection so that it converges to the reflected root, not the pass-through one.
  subroutine stage_reflect(self, j, tau2, e_minus, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau2, e_minus
    integer, intent(out) :: stat
    integer :: m, nx0, info, stat_b
    real(dp) :: num, den, mu0, mirror
    logical :: done, passed_through
    character(len=40) :: what
    character(len=48) :: what_impulse
    m = self%m; nx0 = self%nsub
    self%impact_condition = self%settings%impact_energy
    what = wall_label('stage 2 (reflecting at wall ', j)
    call self%sys%eval_gap_gradient(self%q_wall, j, self%wall_grad, stat)
    if (stat /= VCI_OK) then
      call set_cause(self, 'gap gradients at the wall'); return
    end if
    call self%sys%set_wall_normal(self%wall_grad)
    if (self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN .and. m == 0 .and. self%rates_first) then
      call reflect_by_rates(done)
      if (done .or. stat /= VCI_OK) return
    end if
    ! the motion with no impulse, and its sensitivity d = d(q_next, lambda)/d mu
    self%q_guess = self%q_wall + tau2 * self%chord_velocity
    call self%sys%put_endpoint(self%x, self%q_wall, self%q_guess)
    call substep(self, self%q_wall, self%p_arrive, tau2, stat)
    if (stat /= VCI_OK) return
    call self%sys%get_endpoint(self%x, self%q_trial)
    num = dot_product(self%sys%grad, self%q_trial - self%q_wall)
    if (.not. num < 0.0_dp .and. self%settings%poke_samples) then
      call poke_departure(self, tau2, num, stat)
      if (stat /= VCI_OK) return
    end if
    mu0 = 0.0_dp; mirror = 0.0_dp
    if (num < 0.0_dp) then
      self%q_trial = -self%sys%grad
      call self%sys%momentum_rhs(self%q_trial, self%rhs(1:nx0))
      ! the sub-step's own Newton factors when its fused solve kept them, else a new Jacobian
      done = .false.
      if (self%fused) call self%sys%substep_sensitivity(self%rhs(1:nx0), done)
      info = 0
      if (.not. done) then
        ! (the Jacobian in the system's declared structure: with a band, no n x n array)
        call self%sys%residual(self%x(1:nx0), self%res(1:nx0), self%res_scale(1:nx0), stat)
        call self%sys%momentum_rhs(self%q_trial, self%rhs(1:nx0))
        if (stat == VCI_OK) call self%newton%jacobian_solve(self%sys, self%x(1:nx0), self%res(1:nx0), self%jac, &
                                                           self%rhs(1:nx0), info, stat)
        if (stat /= VCI_OK) then
          call set_cause(self, trim(what)//' initial guess'); return
        end if
      end if
      call self%sys%endpoint_direction(self%rhs(1:nx0), self%q_trial)   ! a sensitivity, not a point
      den = dot_product(self%sys%grad, self%q_trial)
      if (info /= 0 .or. .not. (abs(den) > 0.0_dp) .or. .not. ieee_is_finite(den)) then
        stat = VCI_ERR_IMPACT
        self%cause = trim(what)//': the motion does not depend on the impulse (singular normal direction)'
        return
      end if
      mu0 = -2.0_dp * num / den
      self%x(1:nx0) = self%x(1:nx0) + mu0 * self%rhs(1:nx0)
      mirror = mu0
      if (self%settings%impact_energy /= VCI_IMPACT_HAMILTONIAN) then
        self%x_saved(1:nx0) = self%x(1:nx0)    ! the mirror start, for a retry or a fallback from it
        self%x_low(1:nx0) = self%x(1:nx0)      ! (x_saved is scratch for reflected())
        call energy_along(self, nx0, tau2, e_minus, mu0, 0.25_dp, stat)
        if (stat /= VCI_OK) then
          call set_cause(self, trim(what)//' initial guess'); return
        end if
      end if
    end if
    ! num >= 0: the free motion from the wall already moves into the admissible set (a graze);
    ! no impulse is needed and the sub-step stands as computed.
    call self%sys%put_extra(self%x, KIND_STAGE2, mu0)
    if (self%m > 0) self%constraint_impulse = 0.0_dp
    if (mu0 /= 0.0_dp .and. self%settings%impact_energy == VCI_IMPACT_HAMILTONIAN) then
      call reflect_hamiltonian(e_minus, stat)
    else if (mu0 /= 0.0_dp) then
      call self%sys%pose_stage2(self%q_wall, self%p_arrive, tau2, j, e_minus)
      call run_newton(self, self%sys%unknowns(KIND_STAGE2), what(1:len_trim(what)), stat)
      if (stat == VCI_ERR_NEWTON .and. mu0 /= mirror) then
        ! energy_along's start did not lead to a solution: Newton once more from the mirror
        self%x(1:nx0) = self%x_saved(1:nx0)
        call self%sys%put_extra(self%x, KIND_STAGE2, mirror)
        call run_newton(self, self%sys%unknowns(KIND_STAGE2), what(1:len_trim(what)), stat)
      end if
      passed_through = .false.
      if (stat == VCI_OK) then
        if (.not. reflected(self, self%sys%get_extra(self%x, KIND_STAGE2), tau2, stat)) then
          if (stat /= VCI_OK) return
          stat = VCI_ERR_NEWTON               ! the pass-through root: not the reflection
          passed_through = .true.
        end if
      end if
      if (stat == VCI_ERR_NEWTON) then
        call reflect_from_departure(self, j, nx0, tau2, e_minus, mirror, what(1:len_trim(what)), stat)
        if (stat == VCI_OK) then
          passed_through = .false.
          if (.not. reflected(self, self%sys%get_extra(self%x, KIND_STAGE2), tau2, stat)) then
            if (stat /= VCI_OK) return
            stat = VCI_ERR_NEWTON
            passed_through = .true.
          end if
        end if
        self%x_saved(1:nx0) = self%x_low(1:nx0)
      end if
      if (self%has_energy .and. m == 0 .and. (stat == VCI_OK .or. stat == VCI_ERR_NEWTON)) then
        ! Near a graze the discrete condition blends with H (docs/BACKWARD.md, "A reversible energy
        ! condition"): the discrete root stands where the weight is 1 there; else, or where the
        ! discrete row has no root, the blended row's root is sought. Both directions then solve the
        ! same equation.
        if (stat == VCI_OK) then
          ! from mu0, the start the discrete solve took (the mirror moved by energy_along): both
          ! directions take it the same way (from the discrete root itself, or from H's root, the
          ! search reached another crossing of the row in soft ellipse runs: docs/BACKWARD.md)
          call blend_weight(self, j, tau2, e_minus, stat)
          if (stat /= VCI_OK) return
          if (self%sys%blend_w < 1.0_dp) call reflect_blended(stat)
        else
          ! no discrete root: from H's root
          self%x(1:nx0) = self%x_low(1:nx0)
          mu0 = mirror
          call self%sys%hamiltonian(self%q_wall, self%p_arrive, self%e_fallback, stat)
          if (stat /= VCI_OK) then
            call set_cause(self, trim(what)//' energy H of the arriving momentum'); return
          end if
          call reflect_hamiltonian(self%e_fallback, stat)
          if (stat == VCI_OK) then
            call reflect_blended(stat)
          else if (stat == VCI_ERR_IMPACT) then
            stat = VCI_ERR_NEWTON
          end if
        end if
        if (stat /= VCI_OK .and. stat /= VCI_ERR_NEWTON) return
        self%x_saved(1:nx0) = self%x_low(1:nx0)
        passed_through = .false.
      end if
      if (stat == VCI_ERR_NEWTON .and. self%has_energy) then
        ! No impulse makes E_d of the leaving sub-step equal E-: E_d differs from H by O(h^2)
        ! terms that depend on the sub-step's length (for uniform gravity H changes by
        ! m g^2 h^2 (1 - 2 alpha) / 8 at an impact), and near a graze the normal kinetic energy is
        ! smaller than that difference. This impact keeps H(qt, p+) = H(qt, p-) instead; the record
        ! says so (vci_impact_t%condition) and the statistics count it (energy_fallbacks).
        self%x(1:nx0) = self%x_saved(1:nx0)
        mu0 = mirror
        call self%sys%hamiltonian(self%q_wall, self%p_arrive, self%e_fallback, stat)
        if (stat /= VCI_OK) then
          call set_cause(self, trim(what)//' energy H of the arriving momentum'); return
        end if
        self%impact_condition = VCI_IMPACT_HAMILTONIAN
        self%stats%energy_fallbacks = self%stats%energy_fallbacks + 1
        call reflect_hamiltonian(self%e_fallback, stat)
      else if (stat == VCI_ERR_NEWTON .and. passed_through) then
        stat = VCI_ERR_IMPACT
        self%cause = trim(what)//': the reflected motion does not leave the wall'
      end if
    else
      self%last_residual = 0.0_dp
    end if
  contains
    !> The hamiltonian condition without constraints needs no free motion (issue 28: it and its
    !> sensitivity were ~29 % of an impact on the banded chain): H(qt, p- + mu grad g) = E- fixes
    !> mu from the momenta, and the free motion served only to say whether an impulse is needed and
    !> to start Newton. Here the rate s(mu) at which the motion leaves the wall (normal_rate) says
    !> it where it is clear: the motion at the wall moves into it (s(0) < -noise) and the sub-step
    !> ends beyond wall j by at least half the normal distance s(0) tau2 (so a normal force turns
    !> the normal velocity by less than |s(0)| over tau2: the free motion, g about s(0) t + a t^2/2,
    !> still moves into the wall at its end and ends beyond it, num < 0). The impulse starts at the
    !> other root of the parabola through H at mu = -mu_t, 0, mu_t (fold_by_values: exact where H
    !> is quadratic in p, as the mirror is where the free motion is linear) when its round-off is
    !> within rtol, and the leaving sub-step from the chord velocity with its normal part
    !> reflected; reflect_hamiltonian does the rest. done = .false. (nothing changed): a graze or a
    !> sub-step ending near the wall, a fold that round-off does not resolve to rtol, or a
    !> reflection that failed from this start — the free motion as before.
    subroutine reflect_by_rates(done)
      logical, intent(out) :: done
      real(dp) :: s0, noise0, mu_t, gg, gv
      logical :: resolved
      done = .false.
      call normal_rate(self, 0.0_dp, s0, noise0, stat)
      if (stat /= VCI_OK) return
      if (.not. (s0 < -noise0 .and. self%gaps_end(j) <= 0.5_dp * s0 * tau2)) return
      mu_t = maxval(abs(self%p_arrive)) / max(maxval(abs(self%sys%grad)), tiny(1.0_dp))
      if (.not. (mu_t > 0.0_dp .and. mu_t <= huge(1.0_dp))) return
      call fold_by_values(self, mu_t, mu0, resolved, stat)
      if (stat /= VCI_OK .or. .not. resolved) return
      if (.not. (abs(mu0) > 0.0_dp .and. abs(mu0) <= huge(1.0_dp))) return
      gg = dot_product(self%sys%grad, self%sys%grad)
      gv = dot_product(self%sys%grad, self%chord_velocity)
      self%q_guess = self%q_wall + tau2 * (self%chord_velocity - (2.0_dp * gv / gg) * self%sys%grad)
      call self%sys%put_endpoint(self%x, self%q_wall, self%q_guess)
      call self%sys%put_extra(self%x, KIND_STAGE2, mu0)
      call reflect_hamiltonian(e_minus, stat)
      if (stat == VCI_OK) then
        done = .true.; return
      end if
      if (self%sys%unrecoverable .or. stat == VCI_ERR_CALLBACK) return
      stat = VCI_OK                  ! (the free motion's path poses everything again)
    end subroutine reflect_by_rates

    !> Stage 2 with the blended energy row, from the impulse mu0 (the discrete solve's start, or H's
    !> root with its leaving sub-step in x). Posed on the impulse alone: each value of mu is a regular sub-step from
    !> p- + mu grad g, and the row f(mu) is then evaluated (vci_scheme: blended_row). Full Newton on
    !> the blended system stalled (30 iterations at a scaled residual ~1, or no decrease): the row
    !> has kinks where the weight reaches 1 and where min(K-, K+) switches sides. The reflection's
    !> root is where f rises through 0 (f < 0 between it and the pass-through root near mu = 0):
    !> steps of 5 % of mu0 towards it from mu0 bracket it without reaching that other root, and
    !> Illinois steps close the bracket to the row's tolerance. On success the impact's condition is
    !> the discrete one where the weight is 1 at the root (both directions find the same root), else
    !> VCI_IMPACT_BLENDED, counted with the fallbacks. stat VCI_ERR_NEWTON: no root found.
    subroutine reflect_blended(stat)
      integer, intent(out) :: stat
      integer, parameter :: max_probes = 40, max_refine = 60
      integer :: k, kept
      real(dp) :: mu_lo, mu_hi, f_lo, f_hi, mu, f, tol, step, wlo, whi, delta0
      mu = mu0
      stat = VCI_OK
      if (.not. blended_at(mu, f, tol)) then
        stat = stat_b; return
      end if
      delta0 = self%sys%blend_delta     ! the scheme's offset at the start (see blend_resolved)
      ! to well below the row's tolerance (1e-4 of it, or the bracket at round-off): the state
      ! leaving a soft impact moves by the energy's error over the normal velocity, which is small
      if (abs(f) > 1.0e-4_dp * tol .and. f /= 0.0_dp) then
        ! bracket: f(mu_lo) < 0 < f(mu_hi), stepping from mu0 against the sign of f
        step = -sign(0.05_dp * abs(mu0), f) * sign(1.0_dp, mu0)
        mu_lo = mu; f_lo = f; mu_hi = mu; f_hi = f
        do k = 1, max_probes
          mu = mu + step
          if (.not. (mu / mu0 > 0.0_dp)) exit          ! never through mu = 0
          if (.not. blended_at(mu, f, tol)) then
            stat = stat_b; return
          end if
          if (f == 0.0_dp) exit
          if ((f > 0.0_dp) .neqv. (f_lo > 0.0_dp)) exit
          f_lo = f; mu_lo = mu
          if (step * sign(1.0_dp, mu0) > 0.0_dp) step = 2.0_dp * step   ! outwards the function only rises
        end do
        if (f /= 0.0_dp) then
          if (.not. ((f > 0.0_dp) .neqv. (f_lo > 0.0_dp))) then
            stat = VCI_ERR_NEWTON
            self%cause = trim(what)//': the blended energy condition has no root near the reflection'
            return
          end if
          mu_hi = mu; f_hi = f
          wlo = f_lo; whi = f_hi; kept = 0
          do k = 1, max_refine
            mu = mu_lo - wlo * (mu_hi - mu_lo) / (whi - wlo)
            if (.not. blended_at(mu, f, tol)) then
              stat = stat_b; return
            end if
            if (abs(f) <= 1.0e-4_dp * tol .or. abs(mu_hi - mu_lo) <= 8.0_dp * epsilon(1.0_dp) * abs(mu)) exit
            call illinois_update(mu, f, mu_lo, f_lo, wlo, mu_hi, f_hi, whi, kept)
          end do
          if (abs(f) > tol) then
            stat = VCI_ERR_NEWTON
            self%cause = trim(what)//': the blended energy condition did not converge'
            return
          end if
        end if
      end if
      self%last_residual = abs(f) / tol
      if (.not. reflected(self, mu, tau2, stat)) then
        if (stat == VCI_OK) stat = VCI_ERR_NEWTON
        self%cause = trim(what)//': the motion of the blended energy condition does not leave the wall'
        return
      end if
      ! the weight and energies at the root (reflected() may have posed another system)
      call blend_weight(self, j, tau2, e_minus, stat)
      if (stat /= VCI_OK) return
      if (self%sys%blend_w < 1.0_dp .and. .not. blend_resolved(self%sys%blend_w, self%sys%blend_delta, delta0, tol)) then
        stat = VCI_ERR_IMPACT
        call vci_set_message(self%cause, trim(what)//': the blended energy condition''s root changes H by '// &
          trim(vci_real_text(self%sys%blend_w * abs(self%sys%blend_delta), '(es9.2)'))//', more than twice the '// &
          'scheme''s energy offset at the reflection ('//trim(vci_real_text(abs(delta0), '(es9.2)'))// &
          '): the leaving sub-step does not resolve the motion; a shorter step does')
        return
      end if
      if (self%sys%blend_w < 1.0_dp) then
        self%impact_condition = VCI_IMPACT_BLENDED
        self%e_fallback = self%sys%blend_e_before
        self%e_blend_after = self%sys%blend_e_after
        self%stats%energy_fallbacks = self%stats%energy_fallbacks + 1
      else
        self%impact_condition = VCI_IMPACT_DISCRETE
      end if
    end subroutine reflect_blended

    !> The blended row at impulse mu: the leaving sub-step from p- + mu grad g (Newton from x), its
    !> E_d, the row f and its tolerance. False when a solve or a callback failed (stat says which;
    !> a solve that did not converge is VCI_ERR_NEWTON).
    logical function blended_at(mu, f, tol)
      real(dp), intent(in) :: mu
      real(dp), intent(out) :: f, tol
      real(dp) :: e_out, sc
      blended_at = .false.
      f = huge(1.0_dp); tol = 0.0_dp
      self%p_leave = self%p_arrive + mu * self%sys%grad
      call substep(self, self%q_wall, self%p_leave, tau2, stat_b)
      if (stat_b == VCI_OK) then
        call self%sys%put_extra(self%x, KIND_STAGE2, mu)
        call self%sys%energy_out(self%x, self%q_wall, tau2, e_out, stat_b)
      end if
      if (stat_b == VCI_OK) then
        call self%sys%pose_stage2(self%q_wall, self%p_arrive, tau2, j, e_minus)
        call self%sys%pose_blend(stat_b)
      end if
      if (stat_b == VCI_OK) call self%sys%blended_row(e_out, mu, f, sc, stat_b)
      if (stat_b /= VCI_OK) then
        if (.not. self%sys%unrecoverable .and. stat_b /= VCI_ERR_CALLBACK) stat_b = VCI_ERR_NEWTON
        return
      end if
      tol = self%settings%atol + self%settings%rtol * sc
      blended_at = ieee_is_finite(f)
      if (.not. blended_at) stat_b = VCI_ERR_NEWTON
    end function blended_at

    !> H(qt, p+) = e_ref fixes the impulse from the momenta alone (with constraints, together with
    !> the constraint impulse nu that makes the outgoing velocity admissible); the leaving sub-step
    !> is then a regular one from p- + mu grad g (Omega nu is absorbed by its multiplier). x holds
    !> the mirror start and mu0 its impulse.
    subroutine reflect_hamiltonian(e_ref, stat)
      real(dp), intent(in) :: e_ref
      integer, intent(out) :: stat
      real(dp) :: s0, s1, noise
      self%x_saved(1:nx0) = self%x(1:nx0)
      if (m == 0) then
        ! Newton from a start on the falling side of H along the impulse line (the mirror of a long,
        ! curved sub-step can be: 1.33 for a reflection at 3.42 on Kepler below the wall, h = 0.8)
        ! goes to the pass-through root mu = 0: start from twice the fold instead (the rate's zero
        ! by a secant from mu = 0; exact where H is quadratic in p)
        call normal_rate(self, 0.0_dp, s0, noise, stat)
        if (stat == VCI_OK) call normal_rate(self, mu0, s1, noise, stat)
        if (stat /= VCI_OK) return
        if (s1 < -noise .and. s0 < s1) mu0 = 2.0_dp * mu0 * s0 / (s0 - s1)
      end if
      self%x(1:m) = 0.0_dp                       ! the impulse system's unknowns: [nu(m), mu]
      call self%sys%put_extra(self%x, KIND_IMPULSE, mu0)
      call self%sys%pose_impulse(self%q_wall, self%p_arrive, e_ref)
      if (m > 0) then
        ! start nu where the outgoing velocity satisfies the constraints for the estimated mu
        ! (one linear solve: exact when H is quadratic in p)
        call self%sys%residual(self%x(1:m + 1), self%res(1:m + 1), self%res_scale(1:m + 1), stat)
        if (stat == VCI_OK) call self%sys%jacobian(self%x(1:m + 1), self%res(1:m + 1), self%jac(1:m + 1, 1:m + 1), stat)
        if (stat /= VCI_OK) then
          call set_cause(self, trim(what)//' impulse initial guess'); return
        end if
        self%rhs(1:m) = -self%res(1:m)
        call self%newton%linear_solve(m, self%jac, self%rhs, info)
        if (info == 0) self%x(1:m) = self%rhs(1:m)
      end if
      what_impulse = what   ! what//' impulse' without a heap temporary (trim() and // allocate)
      what_impulse(len_trim(what) + 1:) = ' impulse'
      call run_newton(self, m + 1, what_impulse(1:len_trim(what_impulse)), stat)
      if (stat /= VCI_OK) return
      mu0 = self%sys%get_extra(self%x, KIND_IMPULSE)
      if (m > 0) self%constraint_impulse = self%x(1:m)
      self%x(1:nx0) = self%x_saved(1:nx0)
      self%p_leave = self%p_arrive + mu0 * self%sys%grad
      call substep(self, self%q_wall, self%p_leave, tau2, stat)
      if (stat /= VCI_OK) return
      call self%sys%put_extra(self%x, KIND_STAGE2, mu0)
      if (.not. reflected(self, mu0, tau2, stat)) then
        if (stat == VCI_OK) stat = VCI_ERR_IMPACT
        self%cause = trim(what)//': the reflected motion does not leave the wall'
      end if
    end subroutine reflect_hamiltonian
  end subroutine stage_reflect

  !> The blended row's weight at stage 2's solution in x (vci_scheme: blended_row): sys%blend_w and
  !> the two sides' blended energies.
  subroutine blend_weight(self, j, tau2, e_minus, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j
    real(dp), intent(in) :: tau2, e_minus
    integer, intent(out) :: stat
    real(dp) :: e_out, r, sc
    call self%sys%pose_stage2(self%q_wall, self%p_arrive, tau2, j, e_minus)
    call self%sys%pose_blend(stat)
    if (stat == VCI_OK) call self%sys%energy_out(self%x, self%q_wall, tau2, e_out, stat)
    if (stat == VCI_OK) call self%sys%blended_row(e_out, self%sys%get_extra(self%x, KIND_STAGE2), r, sc, stat)
    if (stat /= VCI_OK) call set_cause(self, 'stage 2: the weight of the blended energy condition')
  end subroutine blend_weight

  !> Does a blended root (weight w < 1, offset delta there) stay within what the scheme's truncation
  !> allows? (issue 27) At the root H+ - H- = -w delta, with delta = (E_d+ - H+) - (E_d- - H-) the
  !> difference of the two sub-steps' energy offsets, O(tau^2) for the midpoint rule and O(tau^(2s))
  !> for Lobatto. The blended condition assumes delta a property of the sub-step lengths, nearly
  !> independent of the impulse (uniform gravity: g^2 h^2 (2 alpha - 1), docs/BACKWARD.md); so H
  !> may move by about |delta0|, the offset at the search's start (the reflection that keeps H or
  !> the discrete solve's start). Where the search has reached an impulse whose leaving sub-step no
  !> longer resolves the motion, delta there is O(1) and many times delta0: Kepler below the wall,
  !> lobatto s = 2, h = 0.6, delta 1.14 against 0.103, H down by 0.72 into an orbit with pericentre
  !> 0.12, the sub-step's own H change then 1.72. Measured on every blend of the default suite's
  !> stability, reversal and fuzz tests and the long-steps table: |w delta| <= 1.17 |delta0| on the
  !> motion's branch; 6.9 and 2.8 (the walled pendulum, midpoint at h omega = 2.5) where not. The
  !> bound 2 |delta0| (plus the row's tolerance, for delta0 at round-off) lies between.
  pure logical function blend_resolved(w, delta, delta0, tol)
    real(dp), intent(in) :: w, delta, delta0, tol
    blend_resolved = w * abs(delta) <= 2.0_dp * abs(delta0) + tol
  end function blend_resolved

  !> Stage 2's second start, when Newton from the mirror failed or found the pass-through root. The
  !> mirror mirrors the end of the free sub-step: where a force bends that sub-step back towards the
  !> wall (its end only just beyond it) the impulse is a fraction of the reflection's (0.050 for 0.47
  !> in core_reversal) and Newton converged to mu = 0; where the mass depends on the velocity (L
  !> quartic in it) the linearised impulse is off by more than the search's 25 % (issue 24). This
  !> start mirrors the free motion's departure instead (a regular sub-step of 1e-3 tau2 from the
  !> wall), and the secant search on the impulse line may move it as far as the reflection's branch
  !> goes (see energy_along). On entry x_low holds the mirror start, rhs the sensitivity d; on return
  !> x holds Newton's result (stat VCI_ERR_NEWTON when there is none).
  subroutine reflect_from_departure(self, j, nx0, tau2, e_minus, mirror, what, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: j, nx0
    real(dp), intent(in) :: tau2, e_minus, mirror
    character(len=*), intent(in) :: what
    integer, intent(out) :: stat
    real(dp), parameter :: eps_frac = 1.0e-3_dp
    real(dp) :: den, num, mu
    ! the free sub-step's start (mu = 0) from the mirror start
    self%x_high(1:nx0) = self%x_low(1:nx0) - mirror * self%rhs(1:nx0)
    call self%sys%endpoint_direction(self%rhs(1:nx0), self%q_trial)
    den = dot_product(self%sys%grad, self%q_trial)
    self%q_guess = self%q_wall + eps_frac * tau2 * self%chord_velocity
    call self%sys%put_endpoint(self%x, self%q_wall, self%q_guess)
    call substep(self, self%q_wall, self%p_arrive, eps_frac * tau2, stat)
    if (stat /= VCI_OK) then
      if (.not. self%sys%unrecoverable) stat = VCI_ERR_NEWTON
      return
    end if
    call self%sys%get_endpoint(self%x, self%q_trial)
    num = dot_product(self%sys%grad, self%q_trial - self%q_wall) / eps_frac
    stat = VCI_ERR_NEWTON
    if (.not. (num < 0.0_dp .and. abs(den) > 0.0_dp)) return     ! departs from the wall: no reflection
    mu = -2.0_dp * num / den
    if (.not. ieee_is_finite(mu)) return
    self%x(1:nx0) = self%x_high(1:nx0) + mu * self%rhs(1:nx0)
    call energy_along(self, nx0, tau2, e_minus, mu, 3.0_dp, stat)
    if (stat /= VCI_OK) return
    call self%sys%put_extra(self%x, KIND_STAGE2, mu)
    call self%sys%pose_stage2(self%q_wall, self%p_arrive, tau2, j, e_minus)
    call run_newton(self, self%sys%unknowns(KIND_STAGE2), what, stat)
  end subroutine reflect_from_departure

  !> Stage 2's start with the E_d condition: x = x0 + mu d (d = rhs, the sensitivity to the impulse)
  !> moves mu from the mirror image mu0 towards E_d(x) = E-, by secant steps on that line (a few
  !> evaluations of E_d where a Newton iteration costs a Jacobian with differenced columns). The
  !> mirror leaves E_d off by the potential's change over the reflected sub-step (1e-3 relative on
  !> the ellipse), which took Newton three iterations. The mu with the smallest |E_d - E-| is taken,
  !> within max_move of mu0 (relative); otherwise the mirror start stays. A callback's
  !> failure ends the search (Newton meets it again and reports it), unless the callback declared
  !> it unrecoverable: then stat says so.
  !> E_d(mu) - E- is about quadratic with roots at the reflection and at the pass-through motion
  !> (mu = 0), and flat half-way; near a graze the two are close (or E_d never reaches E-). With
  !> max_move = 0.25 (the first start) the search stays near the mirror, where Newton converges to
  !> the reflection. A larger max_move (the second start) goes as far as the reflection's branch:
  !> every secant step must keep mu's sign and a slope of the reflection's sign (E_d - E- grows with
  !> |mu| past the reflection; half-way to mu = 0 the slope changes sign), so that it cannot cross
  !> the flat part to the pass-through root.
  subroutine energy_along(self, nx0, tau2, e_minus, mu0, max_move, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: nx0
    real(dp), intent(in) :: tau2, e_minus, max_move
    real(dp), intent(inout) :: mu0
    integer, intent(out) :: stat
    integer, parameter :: max_secants = 3, max_branch_secants = 8
    integer :: k, secants
    real(dp) :: mu_a, mu_b, mu_c, g_a, g_b, g_c, mu_best, g_best
    call self%sys%clear_failure()
    self%sys%unrecoverable = .false.
    mu_best = mu0; g_best = huge(1.0_dp)
    mu_a = mu0
    if (energy_gap(mu_a, g_a)) then
      ! the mirror already meets the energy row's tolerance (e.g. a graze, where E_d hardly
      ! depends on mu and secants would only move mu by round-off): Newton takes it from there
      if (g_best <= self%settings%atol + self%settings%rtol * (abs(g_a + e_minus) + abs(e_minus))) then
        stat = VCI_OK; return
      end if
      mu_b = 0.99_dp * mu0
      secants = max_secants
      if (max_move > 0.25_dp) secants = max_branch_secants
      if (energy_gap(mu_b, g_b)) then
        do k = 1, secants
          if (g_b == g_a) exit
          if (max_move > 0.25_dp .and. .not. ((g_b - g_a) / (mu_b - mu_a) * sign(1.0_dp, mu0) > 0.0_dp)) exit
          mu_c = mu_b - g_b * (mu_b - mu_a) / (g_b - g_a)
          if (.not. (abs(mu_c / mu0 - 1.0_dp) <= max_move .and. mu_c / mu0 > 0.0_dp)) exit
          if (.not. energy_gap(mu_c, g_c)) exit
          if (abs(mu_c - mu_b) <= 1.0e-10_dp * abs(mu0)) exit
          mu_a = mu_b; g_a = g_b; mu_b = mu_c; g_b = g_c
        end do
      end if
    end if
    self%x(1:nx0) = self%x(1:nx0) + (mu_best - mu0) * self%rhs(1:nx0)
    mu0 = mu_best
    if (self%sys%unrecoverable) stat = VCI_ERR_CALLBACK
  contains
    !> E_d - E- at x0 + mu d (in x_try); the best mu so far. False when the evaluation failed.
    logical function energy_gap(mu, g)
      real(dp), intent(in) :: mu
      real(dp), intent(out) :: g
      self%x_try(1:nx0) = self%x(1:nx0) + (mu - mu0) * self%rhs(1:nx0)
      call self%sys%energy_out(self%x_try(1:nx0), self%q_wall, tau2, g, stat)
      g = g - e_minus
      energy_gap = stat == VCI_OK .and. ieee_is_finite(g)
      stat = VCI_OK
      if (energy_gap .and. abs(g) < g_best) then
        mu_best = mu; g_best = abs(g)
      end if
    end function energy_gap
  end subroutine energy_along

  !> Did stage 2 find the reflection? Yes when the sub-step ends on the admissible side of the wall.
  !> A strongly curved sub-step (gravity or a stiff force towards the wall) may leave the wall and
  !> come back to end beyond it: then the motion must depart from the wall — the end of a short
  !> sub-step (1e-3 tau2) from (qt, p- + mu grad g) is on the admissible side — and the re-entry is
  !> the next impact of this step. The pass-through root departs into the wall.
  logical function reflected(self, mu, tau2, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: mu, tau2
    integer, intent(out) :: stat
    real(dp), parameter :: eps_frac = 1.0e-3_dp
    integer :: nx
    real(dp) :: rate, noise
    stat = VCI_OK
    reflected = .false.
    ! the branch first: a root whose momentum still moves into the wall is not the reflection,
    ! wherever its sub-step ends (issue 27: through the centre of Kepler's force, below the wall;
    ! with constraints, the knife between walls at h = 3, whose pass-through sub-step turned back)
    if (self%has_energy) then
      call normal_rate(self, mu, rate, noise, stat)
      if (stat /= VCI_OK) return
      if (rate < -noise) return
    end if
    call self%sys%get_endpoint(self%x, self%q_trial)
    reflected = dot_product(self%sys%grad, self%q_trial - self%q_wall) > 0.0_dp
    if (reflected) return
    nx = self%sys%unknowns(KIND_STAGE2)
    self%x_saved(1:nx) = self%x(1:nx)
    self%q_guess = self%q_wall + eps_frac * (self%q_trial - self%q_wall)
    call self%sys%put_endpoint(self%x, self%q_wall, self%q_guess)
    self%p_leave = self%p_arrive + mu * self%sys%grad
    call substep(self, self%q_wall, self%p_leave, eps_frac * tau2, stat)
    call self%sys%get_endpoint(self%x, self%q_trial)
    reflected = stat == VCI_OK .and. dot_product(self%sys%grad, self%q_trial - self%q_wall) > 0.0_dp
    self%x(1:nx) = self%x_saved(1:nx)
    if (.not. reflected) stat = VCI_OK
  end function reflected

  !> The rate at which the continuous motion from (qt, p- + mu grad g) leaves the wall in the run's
  !> direction, dir grad g . dH/dp (central difference in p along grad g; rate > 0: it leaves), and
  !> the difference's round-off (noise). Elastic reflection reverses this rate; the pass-through root
  !> keeps it negative. For H convex in p, H along the impulse line is a parabola-like curve with the
  !> pass-through root (mu = 0) on its falling side and the reflection on its rising side.
  !> With constraints (m > 0) the motion after the impulse is the constrained one: its momentum is
  !> p+ = p- + mu grad g + Omega(qt) nu with Omega^T dH/dp(qt, p+) = 0 (project_momentum; the
  !> scheme's node multipliers at qt or midpoint's discrete constraint make the leaving sub-step's
  !> velocity admissible the same way), and the rate is grad g . dH/dp(qt, p+). It is also
  !> d/dmu H(qt, p+(mu)), since dH/dp . Omega dnu/dmu = 0: the same fold picture on the constrained
  !> impulse line. (The unconstrained rate is not it: for the knife, blade direction t, c = grad g . t,
  !> speed v along the blade, c v < 0 arriving, the constrained rate is c v + mu c^2 / m, the
  !> unconstrained one c v + mu / m: it also counts the impulse's part across the blade, which the
  !> constraint absorbs, and turns positive at mu = -m c v while the motion enters the wall up to
  !> mu = -m v / c.)
  subroutine normal_rate(self, mu, rate, noise, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: mu
    real(dp), intent(out) :: rate, noise
    integer, intent(out) :: stat
    real(dp), parameter :: rel = 6.0e-6_dp   ! ~ eps**(1/3), as vci_scheme's vci_fd_rel
    real(dp) :: d, hp, hm
    rate = 0.0_dp; noise = 0.0_dp
    d = rel * max(abs(mu), maxval(abs(self%p_arrive)) / max(maxval(abs(self%sys%grad)), tiny(1.0_dp)))
    ! H at base + (mu +- d) grad g: base = p- for m = 0 (as before, bit for bit), and with m > 0
    ! p+'s admissible part less mu grad g, in q_guess as scratch (every use of q_guess sets it
    ! first; an automatic array here would be a heap allocation in every impact: test_alloc_free)
    associate (base => self%q_guess)
      stat = VCI_OK
      base = self%p_arrive
      if (self%m > 0) then
        base = self%p_arrive + mu * self%sys%grad
        call self%sys%project_momentum(self%q_wall, base, stat)
        base = base - mu * self%sys%grad
      end if
      if (stat == VCI_OK) then
        self%p_leave = base + (mu + d) * self%sys%grad
        call self%sys%hamiltonian(self%q_wall, self%p_leave, hp, stat)
      end if
      if (stat == VCI_OK) then
        self%p_leave = base + (mu - d) * self%sys%grad
        call self%sys%hamiltonian(self%q_wall, self%p_leave, hm, stat)
      end if
    end associate
    if (stat /= VCI_OK) then
      call set_cause(self, 'stage 2: H along the impulse line (does the reflection leave the wall?)'); return
    end if
    rate = real(self%sys%dir, dp) * (hp - hm) / (2.0_dp * d)   ! backward, q moves along -dH/dp
    noise = 8.0_dp * epsilon(1.0_dp) * (abs(hp) + abs(hm)) / (2.0_dp * d)
  end subroutine normal_rate

  !> The reflection's impulse where H (m = 0) is quadratic along the impulse line: the other root
  !> of H(qt, p- + mu grad g) = H(qt, p-), from the parabola through mu = -mu_t, 0, mu_t,
  !> mu0 = -mu_t (H+ - H-) / (H+ - 2 H0 + H-). At a graze H is mostly the tangential motion's and
  !> the normal part only a small difference of H values: the rate's central difference over
  !> d = 6e-6 mu_t (normal_rate) has round-off eps |H| / (2 d |s(0)|), 9e-9 relative on the
  !> grazing line at normal speed 1e-3 (H = 0.5, mu_t = 1), and a fold from it left the reflected
  !> speed 1.05e-9 off (test_grazing_line), a start the energy row's tolerance, rtol |H|, accepts
  !> (it fixes v_n only to rtol |H| / v_n). Over +-mu_t the round-off of mu0 is about
  !> eps (|H+| + |H-|) / |H+ - H-| relative; resolved = that is within rtol and the curvature is
  !> resolved: then the start is the reflection to solver tolerance wherever H is quadratic in p.
  !> Else the caller takes the free motion's mirror.
  subroutine fold_by_values(self, mu_t, mu0, resolved, stat)
    type(vci_stepper_t), intent(inout) :: self
    real(dp), intent(in) :: mu_t
    real(dp), intent(out) :: mu0
    logical, intent(out) :: resolved
    integer, intent(out) :: stat
    real(dp) :: hp, h0, hm, slope, curvature
    mu0 = 0.0_dp; resolved = .false.
    self%p_leave = self%p_arrive + mu_t * self%sys%grad
    call self%sys%hamiltonian(self%q_wall, self%p_leave, hp, stat)
    if (stat == VCI_OK) call self%sys%hamiltonian(self%q_wall, self%p_arrive, h0, stat)
    if (stat == VCI_OK) then
      self%p_leave = self%p_arrive - mu_t * self%sys%grad
      call self%sys%hamiltonian(self%q_wall, self%p_leave, hm, stat)
    end if
    if (stat /= VCI_OK) then
      call set_cause(self, 'stage 2: H along the impulse line (the reflection''s impulse)'); return
    end if
    slope = hp - hm
    curvature = hp - 2.0_dp * h0 + hm
    resolved = epsilon(1.0_dp) * (abs(hp) + abs(hm)) <= self%settings%rtol * abs(slope) .and. &
               curvature > 8.0_dp * epsilon(1.0_dp) * (abs(hp) + 2.0_dp * abs(h0) + abs(hm))
    if (resolved) mu0 = -mu_t * slope / curvature
  end subroutine fold_by_values

  !> The impact just resolved (stage 1 in x_stage1 / q_wall, stage 2 in x), into imp.
  subroutine record_impact(self, imp, dir, h, t, elapsed, j, e_minus, s1res, tau2)
    type(vci_stepper_t), intent(inout) :: self
    type(vci_impact_t), intent(inout) :: imp
    integer, intent(in) :: dir, j
    real(dp), intent(in) :: h, t, elapsed, e_minus, s1res, tau2
    integer :: n, stat, i, k
    real(dp) :: mu, e_after, acc
    n = self%n
    mu = self%sys%get_extra(self%x, KIND_STAGE2)
    imp%t = t + real(dir, dp) * elapsed
    imp%alpha = elapsed / h
    imp%gap = j
    imp%q = self%q_wall
    imp%p_before = self%p_arrive
    imp%p_after = self%p_arrive + mu * self%sys%grad
    if (self%m > 0 .and. self%impact_condition == VCI_IMPACT_HAMILTONIAN) then
      do i = 1, n   ! + matmul(omega, nu) in matmul's order: its result would be a heap temporary
        acc = 0.0_dp
        do k = 1, self%m
          acc = acc + self%sys%omega(i, k) * self%constraint_impulse(k)
        end do
        imp%p_after(i) = imp%p_after(i) + acc
      end do
    end if
    imp%grad_g = self%sys%grad
    imp%impulse = real(dir, dp) * mu
    imp%energy_before = e_minus
    imp%condition = self%impact_condition
    if (self%impact_condition /= self%settings%impact_energy) imp%energy_before = self%e_fallback
    if (self%impact_condition == VCI_IMPACT_HAMILTONIAN) then
      call self%sys%hamiltonian(self%q_wall, imp%p_after, e_after, stat)
    else if (self%impact_condition == VCI_IMPACT_BLENDED) then
      e_after = self%e_blend_after
    else
      call self%sys%energy_out(self%x, self%q_wall, tau2, e_after, stat)
    end if
    imp%energy_after = e_after
    call self%sys%get_endpoint(self%x, self%q_trial)
    imp%leave_rate = dot_product(self%sys%grad, self%q_trial - self%q_wall) / tau2
    imp%stage1_residual = s1res
    imp%stage2_residual = self%last_residual
  end subroutine record_impact

  !> E_d of the sub-step that would have arrived at the current point in direction dir: one
  !> regular sub-step in the opposite direction (walls ignored). Needed only when a run starts on
  !> a wall moving into it and no previous step is known.
  subroutine arriving_energy(self, dir, h, e, stat)
    type(vci_stepper_t), intent(inout) :: self
    integer, intent(in) :: dir
    real(dp), intent(in) :: h
    real(dp), intent(out) :: e
    integer, intent(out) :: stat
    integer :: nx
    nx = self%sys%unknowns(KIND_STAGE2)
    self%x_saved(1:nx) = self%x(1:nx)
    call self%sys%set_direction(-dir)
    call self%sys%put_endpoint(self%x, self%q_start, self%q_start)
    call self%sys%put_multipliers(self%x, self%zero_lambda)
    call substep(self, self%q_start, self%p_start, h, stat)
    if (stat == VCI_OK) call self%sys%energy_out(self%x, self%q_start, h, e, stat)
    call self%sys%set_direction(dir)
    self%x(1:nx) = self%x_saved(1:nx)
  end subroutine arriving_energy


  !> prefix//j//')' without formatted I/O (an internal write costs ~2.7k instructions, a few per
  !> cent of an impact, for a label read only when the solve fails).
  pure function wall_label(prefix, j) result(label)
    character(len=*), intent(in) :: prefix
    integer, intent(in) :: j
    character(len=40) :: label
    character(len=11) :: digits
    integer :: v, pos
    v = abs(j); pos = len(digits); digits = ''
    do
      digits(pos:pos) = achar(iachar('0') + mod(v, 10))
      v = v / 10
      if (v == 0 .or. pos == 1) exit
      pos = pos - 1
    end do
    ! by substrings: a concatenation of these lengths is built in a heap temporary
    label = prefix
    label(len(prefix) + 1:) = digits(pos:)
    label(len(prefix) + len(digits) - pos + 2:) = ')'
  end function wall_label

  !> 'wall j' (wall_label's text without its closing parenthesis)
  pure function wall_name(j) result(name)
    integer, intent(in) :: j
    character(len=40) :: name
    name = wall_label('wall ', j)
    name(len_trim(name):) = ' '
  end function wall_name
  !> One Illinois step on a root bracketed by a and b (f_a, f_b of opposite signs) with secant
  !> weights w_a, w_b: the end whose f has the sign of f at x moves to x and takes f as its weight;
  !> an end kept a second time in a row has its weight halved, so that both ends move in. kept: 0 at
  !> the start, then -1 when b moved last, 1 when a did.
  pure subroutine illinois_update(x, f, a, f_a, w_a, b, f_b, w_b, kept)
    real(dp), intent(in) :: x, f
    real(dp), intent(inout) :: a, f_a, w_a, b, f_b, w_b
    integer, intent(inout) :: kept
    if ((f > 0.0_dp) .eqv. (f_b > 0.0_dp)) then
      b = x; f_b = f; w_b = f
      if (kept < 0) w_a = 0.5_dp * w_a
      kept = -1
    else
      a = x; f_a = f; w_a = f
      if (kept > 0) w_b = 0.5_dp * w_b
      kept = 1
    end if
  end subroutine illinois_update

end submodule vci_impacts
