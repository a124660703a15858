!> A step loop that watches a run for the stability cases: energy H(q, p) against its start,
!> smallest gap on the grid, Newton work per step, impacts (times, fractions, energies), NaN/Inf,
!> and the status and message of the first failure. Used by the stability suites and by the
!> program that writes the table of docs/STABILITY.md, so both see the same numbers.
module vci_stab_run
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci
  implicit none
  private

  integer, parameter, public :: max_kept = 4096   !< impacts kept in detail per run

  type, public :: run_summary_t
    integer :: status = VCI_OK
    character(len=VCI_MSG_LEN) :: message = ''
    integer(i8) :: steps = 0, impacts = 0, solves = 0, iterations = 0, fallbacks = 0
    integer(i8) :: split_steps = 0, largest_split = 0   !< the safety net's counts (set_step_splits)
    integer :: max_impacts_step = 0        !< most impacts resolved inside one step
    integer :: max_iterations_step = 0     !< most Newton iterations spent on one step
    real(dp) :: h0 = 0.0_dp                !< H(q, p) at the start (or of the first state where H exists)
    real(dp) :: max_dh = 0.0_dp            !< max |H - H0| over the grid
    real(dp) :: min_gap = huge(1.0_dp)     !< smallest gap value on the grid (after the start)
    real(dp) :: max_abs_q = 0.0_dp, max_abs_p = 0.0_dp
    logical :: finite = .true.
    integer :: kept = 0
    real(dp), allocatable :: impact_t(:), impact_alpha(:)  !< the first max_kept impacts: time, fraction
    real(dp), allocatable :: impact_dh(:)    !< H(q~, p+) - H(q~, p-) of each impact
    integer, allocatable :: impact_wall(:)
    real(dp) :: worst_stage_residual = 0.0_dp   !< largest scaled stage 1/2 residual (<= 1: converged)
    real(dp) :: seconds = 0.0_dp                !< wall time of the loop
  end type run_summary_t

  public :: run_steps, energy_of_model, init_summary

contains

  !> A fresh summary with room for max_kept impacts.
  subroutine init_summary(s)
    type(run_summary_t), intent(out) :: s
    allocate (s%impact_t(max_kept), s%impact_alpha(max_kept), s%impact_dh(max_kept), s%impact_wall(max_kept))
    s%impact_t = 0.0_dp; s%impact_alpha = 0.0_dp; s%impact_dh = 0.0_dp; s%impact_wall = 0
  end subroutine init_summary

  !> H(q, p) from the model's energy; ok = .false. where the model has none or it fails there.
  subroutine energy_of_model(model, q, p, e, ok)
    class(vci_model_t), intent(inout) :: model
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    logical, intent(out) :: ok
    integer :: s
    s = 0
    call model%energy(q, p, e, s)
    ok = (s == 0) .and. ieee_is_finite(e)
  end subroutine energy_of_model

  !> Take up to nsteps forward steps of an initialised integrator, stopping at the first failure.
  subroutine run_steps(integ, model, nsteps, s)
    type(vci_integrator_t), intent(inout) :: integ
    class(vci_model_t), intent(inout) :: model
    integer(i8), intent(in) :: nsteps
    type(run_summary_t), intent(out) :: s
    integer(i8) :: k, it0, c0, c1, rate
    integer :: stat, i, st
    real(dp) :: e, eb, ea
    real(dp), allocatable :: g(:)
    logical :: ok, have_h0, oka, okb
    type(vci_stats_t) :: stats
    type(vci_impact_t) :: imp

    call init_summary(s)
    allocate (g(max(1, model%n_gaps)))
    have_h0 = .false.
    call energy_of_model(model, integ%configuration(), integ%momentum(), e, ok)
    if (ok) then
      s%h0 = e; have_h0 = .true.
    end if
    call system_clock(c0, rate)
    do k = 1, nsteps
      stats = integ%statistics(); it0 = stats%newton_iterations
      call integ%step(1, stat)
      stats = integ%statistics()
      s%max_iterations_step = max(s%max_iterations_step, int(stats%newton_iterations - it0))
      if (stat /= VCI_OK) then
        s%status = stat; s%message = integ%message()
        exit
      end if
      s%steps = k
      s%max_impacts_step = max(s%max_impacts_step, integ%impact_count())
      do i = 1, integ%impact_count()
        imp = integ%impact(i)
        s%worst_stage_residual = max(s%worst_stage_residual, imp%stage1_residual, imp%stage2_residual)
        if (s%kept < max_kept) then
          s%kept = s%kept + 1
          s%impact_t(s%kept) = imp%t; s%impact_alpha(s%kept) = imp%alpha; s%impact_wall(s%kept) = imp%gap
          call energy_of_model(model, imp%q, imp%p_before, eb, okb)
          call energy_of_model(model, imp%q, imp%p_after, ea, oka)
          if (oka .and. okb) s%impact_dh(s%kept) = ea - eb
        end if
      end do
      if (.not. (all(ieee_is_finite(integ%configuration())) .and. all(ieee_is_finite(integ%momentum())))) s%finite = .false.
      s%max_abs_q = max(s%max_abs_q, maxval(abs(integ%configuration())))
      s%max_abs_p = max(s%max_abs_p, maxval(abs(integ%momentum())))
      if (model%n_gaps > 0) then
        st = 0
        call model%gaps(integ%configuration(), g, st)
        s%min_gap = min(s%min_gap, minval(g))
      end if
      call energy_of_model(model, integ%configuration(), integ%momentum(), e, ok)
      if (ok) then
        if (.not. have_h0) then
          s%h0 = e; have_h0 = .true.
        end if
        s%max_dh = max(s%max_dh, abs(e - s%h0))
      end if
    end do
    call system_clock(c1)
    s%seconds = real(c1 - c0, dp) / real(rate, dp)
    stats = integ%statistics()
    s%impacts = stats%impacts
    s%solves = stats%newton_solves
    s%iterations = stats%newton_iterations
    s%fallbacks = stats%fallbacks
    s%split_steps = stats%split_steps; s%largest_split = stats%largest_split
  end subroutine run_steps
end module vci_stab_run
