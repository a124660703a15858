!> The stability cases of docs/STABILITY.md (issue 6, part 2), each a subroutine that sets up a
!> scene, runs it through the public API and returns what happened. The suites assert on these
!> results; tools/stability/vci_stability_table.f90 prints them as the table.
module vci_stab_cases
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci
  use vci_scene_particle, only: particle_t, particle_on_floor, particle_in_box
  use vci_scene_ellipse, only: ellipse_t, ellipse_model
  use vci_scene_pendulum, only: pendulum_t, pendulum_model, pendulum_f
  use vci_stab_models, only: massless_t, massless_model
  use vci_stab_run
  implicit none
  private

  real(dp), parameter, public :: pi = acos(-1.0_dp)

  public :: stiff_case, magnitude_case, graze_line_case, graze_ceiling_case, alpha_case
  public :: corner_case, close_walls_case, rest_case, short_bounce_case, channel_case
  public :: pendulum_case, massless_case, step_size_case, ellipse_long_case, growth_exponent

contains

  !> Particle on a vertical spring (omega = h_omega / h, equilibrium y = 1) above the floor y = 0,
  !> started at the equilibrium moving down with amplitude 2: the free oscillation would reach
  !> y = -1, so every period has a bounce. h = 1e-3, nsteps steps, impact condition `mode`.
  subroutine stiff_case(h_omega, mode, nsteps, s, poke)
    real(dp), intent(in) :: h_omega
    integer, intent(in) :: mode
    integer(i8), intent(in) :: nsteps
    type(run_summary_t), intent(out) :: s
    logical, intent(in), optional :: poke   !< set_poke_samples (absent: the default, on)
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp), parameter :: h = 1.0e-3_dp
    real(dp) :: omega
    integer :: stat
    omega = h_omega / h
    model = particle_on_floor(1.0_dp, 9.8_dp)
    model%k = omega**2
    model%y_rest = 1.0_dp + model%grav / model%k
    call integ%create(model, h, stat)
    call integ%set_impact_energy(mode, stat)
    if (present(poke)) call integ%set_poke_samples(poke, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, 1.0_dp], [1.0_dp, -2.0_dp * omega], stat)
    call run_steps(integ, model, nsteps, s)
  end subroutine stiff_case

  !> Drop from (0, 1) with horizontal speed sqrt(g) (mass m, gravity g) and step h = h1/sqrt(g):
  !> in units of length 1 and time 1/sqrt(g) every run is the same. nsteps steps. Returns the run
  !> and the final state in those units (x, y, vx, vy).
  !> splits: the safety net's bound (set_step_splits; absent: the default).
  subroutine magnitude_case(mass, grav, h1, nsteps, mode, s, state, splits)
    real(dp), intent(in) :: mass, grav, h1
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: mode
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: state(4)
    integer, intent(in), optional :: splits
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp) :: h, v
    integer :: stat
    v = sqrt(grav); h = h1 / v
    model = particle_on_floor(mass, grav)
    call integ%create(model, h, stat)
    call integ%set_impact_energy(mode, stat)
    if (present(splits)) call integ%set_step_splits(splits, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, 1.0_dp], [mass * v, 0.0_dp], stat)
    call run_steps(integ, model, nsteps, s)
    associate (q_ => integ%configuration(), p_ => integ%momentum())
      state = [q_(1), q_(2), p_(1) / (mass * v), p_(2) / (mass * v)]
    end associate
    s%impact_t(1:s%kept) = s%impact_t(1:s%kept) * v
  end subroutine magnitude_case

  !> No gravity; a straight approach to the floor with tangential speed 1 and normal speed vn,
  !> crossing at t* = 0.105 (in the middle of step 11 of h = 1e-2). 20 steps. Returns the impact
  !> time, the normal speed after the impact and the tangential speed after. rates_first: the
  !> hamiltonian stage 2's path (set_solver_paths; absent: the default, on).
  subroutine graze_line_case(vn, mode, s, t_star, vn_after, vt_after, rates_first)
    real(dp), intent(in) :: vn
    integer, intent(in) :: mode
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: t_star, vn_after, vt_after
    logical, intent(in), optional :: rates_first
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    integer :: stat
    t_star = 0.105_dp
    model = particle_on_floor(1.0_dp, 0.0_dp)
    call integ%create(model, 1.0e-2_dp, stat)
    call integ%set_impact_energy(mode, stat)
    ! (the linear-algebra paths as by default: in-line LU up to 15 unknowns, reuse from 16)
    if (present(rates_first)) call integ%set_solver_paths(15, 16, rates_first=rates_first)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, vn * t_star], [1.0_dp, -vn], stat)
    call run_steps(integ, model, 20_i8, s)
    associate (p_ => integ%momentum())
      vn_after = p_(2); vt_after = p_(1)
    end associate
  end subroutine graze_line_case

  !> A particle (mass 1, gravity 9.8) in a channel 0 <= y <= yc closed by the side wall x <= xw,
  !> from (0, y0) with velocity (vx, vy), steps of h (the discrete model's own L_d and condition):
  !> several impacts in a step, walls 0.002-0.1 apart. 20 steps. Returns the run (status, impacts)
  !> and, over every impact point, the most negative gap of any wall (0 when none is negative).
  subroutine channel_case(yc, xw, y0, vx, vy, h, s, worst_gap)
    real(dp), intent(in) :: yc, xw, y0, vx, vy, h
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: worst_gap
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    type(vci_impact_t) :: imp
    real(dp) :: g(3)
    integer :: stat, k, i
    call init_summary(s)
    model = particle_on_floor(1.0_dp, 9.8_dp)
    deallocate (model%normal, model%offset)
    model%n_gaps = 3
    allocate (model%normal(2, 3), model%offset(3))
    model%normal = reshape([0.0_dp, 1.0_dp, 0.0_dp, -1.0_dp, -1.0_dp, 0.0_dp], [2, 3])
    model%offset = [0.0_dp, -yc, -xw]
    call integ%create(model, h, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, [0.0_dp, y0], [vx, vy], stat)
    worst_gap = 0.0_dp
    s%status = stat
    do k = 1, 20
      if (s%status /= VCI_OK) exit
      call integ%step(1, s%status)
      if (s%status /= VCI_OK) then
        s%message = integ%message(); exit
      end if
      do i = 1, integ%impact_count()
        imp = integ%impact(i)
        s%impacts = s%impacts + 1
        call model%gaps(imp%q, g, stat)
        worst_gap = min(worst_gap, minval(g))
      end do
    end do
  end subroutine channel_case

  !> Gravity 9.8, ceiling y <= 1 (normal (0, -1)); a parabola whose apex is at height 1 + depth at
  !> time t_apex. h = 1e-2, 60 steps. depth > 0 pokes through the ceiling. t_apex on a grid point or
  !> between two. Returns the run (impacts, smallest gap on the grid).
  subroutine graze_ceiling_case(depth, t_apex, s, poke)
    real(dp), intent(in) :: depth, t_apex
    type(run_summary_t), intent(out) :: s
    logical, intent(in), optional :: poke   !< set_poke_samples (absent: the default, on)
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp), parameter :: g = 9.8_dp
    integer :: stat
    model = particle_on_floor(1.0_dp, g)
    model%normal(:, 1) = [0.0_dp, -1.0_dp]; model%offset(1) = -1.0_dp
    call integ%create(model, 1.0e-2_dp, stat)
    if (present(poke)) call integ%set_poke_samples(poke, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, 1.0_dp + depth - 0.5_dp * g * t_apex**2], &
                                  [1.0_dp, g * t_apex], stat)
    call run_steps(integ, model, 60_i8, s)
  end subroutine graze_ceiling_case

  !> Fall from rest under g = 8 with h = 1/8 (dyadic: the grid positions are exact in binary),
  !> horizontal speed 1/2, reaching the floor at t* = 1 + alpha h: the impact is at fraction
  !> alpha of step 9. alpha = 0 lands exactly on the floor at the grid point t = 1. 24 steps.
  !> Returns t* and the height at t = 3 against the exact elastic bounce.
  subroutine alpha_case(alpha, mode, s, t_star, y_err, x0)
    real(dp), intent(in) :: alpha
    integer, intent(in) :: mode
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: t_star, y_err
    real(dp), intent(in), optional :: x0   !< start abscissa (default 0): the size of the positions
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp), parameter :: g = 8.0_dp, h = 0.125_dp
    real(dp) :: y0, t, y_exact, period
    integer :: stat
    t_star = 1.0_dp + alpha * h
    y0 = 0.5_dp * g * t_star**2
    model = particle_on_floor(1.0_dp, g)
    call integ%create(model, h, stat)
    call integ%set_impact_energy(mode, stat)
    if (present(x0)) then
      call integ%init_from_momentum(0.0_dp, [x0, y0], [0.5_dp, 0.0_dp], stat)
    else
      call integ%init_from_momentum(0.0_dp, [0.0_dp, y0], [0.5_dp, 0.0_dp], stat)
    end if
    call run_steps(integ, model, 24_i8, s)
    ! exact: bounces at t*, 3 t*, ... ; between them y = y0 - g (t - t* - k 2 t*)^2 / 2 shifted
    t = integ%time()
    period = 2.0_dp * t_star
    y_exact = y0 - 0.5_dp * g * (modulo(t - t_star, period) - t_star)**2
    associate (q_ => integ%configuration())
      y_err = q_(2) - y_exact
    end associate
  end subroutine alpha_case

  !> No gravity, unit box; from (c, c) with velocity (-1, -1) into the corner (0, 0) at t = c.
  !> h = 1/8; c = 0.5625 reaches the corner in mid-step, c = 0.5 exactly on the grid. 12 steps.
  !> Returns the final state's error against the exact motion (velocity reversed at t = c).
  subroutine corner_case(c, mode, s, err)
    real(dp), intent(in) :: c
    integer, intent(in) :: mode
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: err
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    integer :: stat
    model = particle_in_box(1.0_dp, 1.0_dp)
    call integ%create(model, 0.125_dp, stat)
    call integ%set_impact_energy(mode, stat)
    call integ%init_from_momentum(0.0_dp, [c, c], [-1.0_dp, -1.0_dp], stat)
    call run_steps(integ, model, 12_i8, s)
    err = max(maxval(abs(integ%configuration() - (integ%time() - c))), maxval(abs(integ%momentum() - 1.0_dp)))
  end subroutine corner_case

  !> No gravity; walls y >= 0 and y <= d, the particle starting at (0, d/2) with velocity (1, v):
  !> about v h / d impacts per step of h = 1e-2. 10 steps. Returns the error of the final y against
  !> the exact folded motion.
  !> splits: the safety net's bound (set_step_splits; absent: the default).
  subroutine close_walls_case(d, v, mode, max_impacts, s, err, splits)
    real(dp), intent(in) :: d, v
    integer, intent(in) :: mode, max_impacts
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: err
    integer, intent(in), optional :: splits
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp) :: u
    integer :: stat
    model = particle_on_floor(1.0_dp, 0.0_dp)
    deallocate (model%normal, model%offset)
    allocate (model%normal(2, 2), model%offset(2))
    model%n_gaps = 2
    model%normal = reshape([0.0_dp, 1.0_dp, 0.0_dp, -1.0_dp], [2, 2])
    model%offset = [0.0_dp, -d]
    call integ%create(model, 1.0e-2_dp, stat)
    call integ%set_impact_energy(mode, stat)
    call integ%set_max_impacts(max_impacts, stat)
    if (present(splits)) call integ%set_step_splits(splits, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, 0.5_dp * d], [1.0_dp, v], stat)
    call run_steps(integ, model, 10_i8, s)
    u = modulo(0.5_dp * d + v * integ%time(), 2.0_dp * d)   ! unfolded coordinate, folded into [0, d]
    associate (q_ => integ%configuration())
      err = abs(q_(2) - merge(u, 2.0_dp * d - u, u <= d)) / d
    end associate
  end subroutine close_walls_case

  !> At rest on the floor (0, 0) under gravity 9.8 with tangential speed vx, h = 1e-2, nsteps.
  subroutine rest_case(vx, mode, nsteps, s)
    real(dp), intent(in) :: vx
    integer, intent(in) :: mode
    integer(i8), intent(in) :: nsteps
    type(run_summary_t), intent(out) :: s
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    integer :: stat
    model = particle_on_floor(1.0_dp, 9.8_dp)
    call integ%create(model, 1.0e-2_dp, stat)
    call integ%set_impact_energy(mode, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, 0.0_dp], [vx, 0.0_dp], stat)
    call run_steps(integ, model, nsteps, s)
  end subroutine rest_case

  !> Bounces of period P = ratio * h (h = 1e-2, gravity 9.8): dropped from y0 = g P^2 / 8 at the
  !> apex. ratio < 1 puts several bounces into one step. nsteps steps. splits: the safety net's
  !> bound (set_step_splits; absent: the default).
  subroutine short_bounce_case(ratio, mode, nsteps, s, splits)
    real(dp), intent(in) :: ratio
    integer, intent(in) :: mode
    integer(i8), intent(in) :: nsteps
    type(run_summary_t), intent(out) :: s
    integer, intent(in), optional :: splits
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp), parameter :: g = 9.8_dp, h = 1.0e-2_dp
    integer :: stat
    model = particle_on_floor(1.0_dp, g)
    call integ%create(model, h, stat)
    call integ%set_impact_energy(mode, stat)
    if (present(splits)) call integ%set_step_splits(splits, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, g * (ratio * h)**2 / 8.0_dp], [1.0_dp, 0.0_dp], stat)
    call run_steps(integ, model, nsteps, s)
  end subroutine short_bounce_case

  !> The paper's pendulum (h, nsteps), or, with start_at_pi, the same velocity started at
  !> theta = pi where sin^2 theta (the phi-block of the Newton matrix) vanishes. Returns the
  !> smallest |sin theta| met on the grid.
  subroutine pendulum_case(h, nsteps, start_at_pi, mode, s, min_sin)
    real(dp), intent(in) :: h
    integer(i8), intent(in) :: nsteps
    logical, intent(in) :: start_at_pi
    integer, intent(in) :: mode
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: min_sin
    type(pendulum_t), target :: model
    type(vci_integrator_t) :: integ
    type(run_summary_t) :: part
    real(dp) :: q0(2), qd(2)
    integer :: stat
    integer(i8) :: k
    model = pendulum_model()
    q0 = [0.75_dp * pi, 0.0_dp]
    if (start_at_pi) q0(1) = pi
    qd = [pi / 4.0_dp, pendulum_f(q0(1)) * pi / 4.0_dp]
    call integ%create(model, h, stat)
    call integ%set_impact_energy(mode, stat)
    call integ%init_from_pair(0.0_dp, q0, q0 + h * qd, stat)
    associate (q_ => integ%configuration())
      min_sin = abs(sin(q_(1)))
    end associate
    ! step in chunks to watch sin(theta) on the grid
    s%status = VCI_OK
    do k = 1, nsteps
      call run_steps(integ, model, 1_i8, part)
      call merge_summary(s, part, k == 1)
      if (part%status /= VCI_OK) exit
      associate (q_ => integ%configuration())
        min_sin = min(min_sin, abs(sin(q_(1))))
      end associate
    end do
  end subroutine pendulum_case

  !> Fold a one-step summary into a running one.
  subroutine merge_summary(s, part, first)
    type(run_summary_t), intent(inout) :: s
    type(run_summary_t), intent(in) :: part
    logical, intent(in) :: first
    integer :: i
    if (first) then
      s = part
      return
    end if
    s%status = part%status; s%message = part%message
    s%steps = s%steps + part%steps
    s%impacts = part%impacts; s%solves = part%solves; s%iterations = part%iterations
    s%fallbacks = part%fallbacks
    s%max_impacts_step = max(s%max_impacts_step, part%max_impacts_step)
    s%max_iterations_step = max(s%max_iterations_step, part%max_iterations_step)
    s%min_gap = min(s%min_gap, part%min_gap)
    s%max_abs_q = max(s%max_abs_q, part%max_abs_q); s%max_abs_p = max(s%max_abs_p, part%max_abs_p)
    s%finite = s%finite .and. part%finite
    s%worst_stage_residual = max(s%worst_stage_residual, part%worst_stage_residual)
    s%seconds = s%seconds + part%seconds
    do i = 1, part%kept
      if (s%kept >= max_kept) exit
      s%kept = s%kept + 1
      s%impact_t(s%kept) = part%impact_t(i); s%impact_alpha(s%kept) = part%impact_alpha(i)
      s%impact_dh(s%kept) = part%impact_dh(i); s%impact_wall(s%kept) = part%impact_wall(i)
    end do
  end subroutine merge_summary

  !> The massless-coordinate model (tied: regular augmented matrix; untied: singular), dropped
  !> from (0, 1, 0) with horizontal speed 1, h = 1e-2, 200 steps (two bounces). Returns the
  !> largest |z - x| on the grid (tied: z follows x) and the largest |z| (untied: z stays put).
  subroutine massless_case(tied, s, max_zx, max_z)
    logical, intent(in) :: tied
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: max_zx, max_z
    type(massless_t), target :: model
    type(vci_integrator_t) :: integ
    type(run_summary_t) :: part
    integer :: stat
    integer(i8) :: k
    model = massless_model(tied)
    call integ%create(model, 1.0e-2_dp, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, 1.0_dp, 0.0_dp], [1.0_dp, 0.0_dp, 0.0_dp], stat)
    max_zx = 0.0_dp; max_z = 0.0_dp
    do k = 1, 200
      call run_steps(integ, model, 1_i8, part)
      call merge_summary(s, part, k == 1)
      if (part%status /= VCI_OK) exit
      associate (q_ => integ%configuration())
        max_zx = max(max_zx, abs(q_(3) - q_(1)))
      end associate
      associate (q_ => integ%configuration())
        max_z = max(max_z, abs(q_(3)))
      end associate
    end do
  end subroutine massless_case

  !> Drop from (0, 1) with horizontal speed 1 under g = 9.8 (first bounce at t1 = sqrt(2/9.8) =
  !> 0.4518, bounce period 0.9035), step h, up to t = t_end (or one step if h is longer). Returns
  !> the first impact time error and the largest relative error of H over the run.
  subroutine step_size_case(h, t_end, mode, s, t1_err, dh_rel)
    real(dp), intent(in) :: h, t_end
    integer, intent(in) :: mode
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: t1_err, dh_rel
    type(particle_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp), parameter :: g = 9.8_dp
    integer :: stat
    integer(i8) :: nsteps
    model = particle_on_floor(1.0_dp, g)
    call integ%create(model, h, stat)
    call integ%set_impact_energy(mode, stat)
    call integ%init_from_momentum(0.0_dp, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], stat)
    nsteps = max(1_i8, nint(t_end / h, i8))
    call run_steps(integ, model, nsteps, s)
    t1_err = huge(1.0_dp)
    if (s%kept > 0) t1_err = s%impact_t(1) - sqrt(2.0_dp / g)
    dh_rel = s%max_dh / s%h0
  end subroutine step_size_case

  !> The paper's ellipse (docs/DESIGN.md §8), h = 1e-2, nsteps steps. Returns the run and, for each
  !> impact i (up to size(e_after)), H just after it minus H0: since free flight conserves H
  !> exactly for this L_d, these are the cumulative energy changes made by the impacts.
  subroutine ellipse_long_case(nsteps, mode, s, e_after, n_e, nonfinite_steps)
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: mode
    type(run_summary_t), intent(out) :: s
    real(dp), intent(out) :: e_after(:)
    integer, intent(out) :: n_e
    integer(i8), intent(out) :: nonfinite_steps
    type(ellipse_t), target :: model
    type(vci_integrator_t) :: integ
    real(dp), parameter :: h = 1.0e-2_dp
    real(dp) :: q0(3), qd(3), e, e0
    type(vci_stats_t) :: stats
    integer :: stat
    integer(i8) :: k, c0, c1, rate
    logical :: ok
    call init_summary(s)
    model = ellipse_model()
    q0 = [pi / 2.0_dp, 0.0_dp, 3.5_dp]; qd = [-3.0_dp, 2.0_dp, 0.0_dp]
    call integ%create(model, h, stat)
    call integ%set_impact_energy(mode, stat)
    call integ%init_from_pair(0.0_dp, q0 - 0.5_dp * h * qd, q0 + 0.5_dp * h * qd, stat)
    call energy_of_model(model, integ%configuration(), integ%momentum(), e0, ok)
    s%h0 = e0
    n_e = 0; nonfinite_steps = 0
    call system_clock(c0, rate)
    do k = 1, nsteps
      call integ%step(1, stat)
      if (stat /= VCI_OK) then
        s%status = stat; s%message = integ%message(); exit
      end if
      s%steps = k
      if (.not. (all(ieee_is_finite(integ%configuration())) .and. all(ieee_is_finite(integ%momentum())))) &
        nonfinite_steps = nonfinite_steps + 1
      if (integ%impact_count() > 0) then
        call energy_of_model(model, integ%configuration(), integ%momentum(), e, ok)
        s%max_dh = max(s%max_dh, abs(e - e0))
        if (n_e < size(e_after)) then
          n_e = n_e + 1; e_after(n_e) = e - e0
        end if
        s%max_impacts_step = max(s%max_impacts_step, integ%impact_count())
      end if
    end do
    call system_clock(c1)
    s%seconds = real(c1 - c0, dp) / real(rate, dp)
    call energy_of_model(model, integ%configuration(), integ%momentum(), e, ok)
    s%max_dh = max(s%max_dh, abs(e - e0))
    s%finite = (nonfinite_steps == 0) .and. ieee_is_finite(e)
    stats = integ%statistics()
    s%impacts = stats%impacts
    s%solves = stats%newton_solves
    s%iterations = stats%newton_iterations
    s%fallbacks = stats%fallbacks
  end subroutine ellipse_long_case

  !> Growth law of a cumulative sequence e(1:n) (the energy after each impact): for lags
  !> L = 1, 2, 4, ... up to n/lag_div, the RMS of e(i+L) - e(i) over all i; the least-squares slope of
  !> log RMS against log L is the exponent (1/2 for a random walk, 1 for a drift, 0 for a bounded
  !> error). rms(1:nlag) and lags(1:nlag) return the points.
  subroutine growth_exponent(e, n, lag_div, beta, lags, rms, nlag)
    real(dp), intent(in) :: e(:)
    integer, intent(in) :: n, lag_div
    real(dp), intent(out) :: beta
    real(dp), intent(out) :: lags(:), rms(:)
    integer, intent(out) :: nlag
    integer :: lag
    real(dp) :: xm, ym
    nlag = 0; lag = 1
    do while (lag <= n / lag_div .and. nlag < size(lags))
      nlag = nlag + 1
      lags(nlag) = real(lag, dp)
      rms(nlag) = sqrt(sum((e(1 + lag:n) - e(1:n - lag))**2) / real(n - lag, dp))
      lag = 2 * lag
    end do
    beta = 0.0_dp
    if (nlag < 2) return
    xm = sum(log(lags(1:nlag))) / nlag; ym = sum(log(rms(1:nlag))) / nlag
    beta = sum((log(lags(1:nlag)) - xm) * (log(rms(1:nlag)) - ym)) / sum((log(lags(1:nlag)) - xm)**2)
  end subroutine growth_exponent
end module vci_stab_cases
