!> Round-off of long fine-step runs (issue 14, item 4). Not a test; run tools/bench/run_roundoff.sh.
!>
!> 1. The paper's ellipse (q0 = (pi/2, 0, 3.5), qdot0 = (-3, 2, 0)) from the exact momenta p0 = M qdot0
!>    with the Hamiltonian impact condition: the midpoint L_d is exact in free flight under uniform
!>    gravity and the Hamiltonian impact is exact for it, so the error at t = 3 s against the exact
!>    event-driven solution (test/support/vci_ref_ellipse.f90, quad precision) is solver tolerance
!>    plus round-off. Four variants separate the two: the hand-derived L_d (unknown q_{k+1}) and the
!>    continuous L with the midpoint scheme (unknown the increment q_{k+1} - q_k), each at the
!>    default tolerance rtol = 1e-12 and at rtol = 1e-15 (Newton to the round-off floor).
!> 2. `--long N H [discrete]`: N steps of the continuous ellipse (midpoint; `discrete`: the
!>    hand-derived L_d) with Hamiltonian impacts at step H; prints the largest |H - H0| up to
!>    t = 2^k H, for a fit of its growth against t.
module roundoff_runs
  use vci
  use vci_scene_ellipse, only: ellipse_t, ellipse_model, ellipse_lagrangian_t, ellipse_lagrangian_model
  implicit none
  private
  public :: run_ellipse

contains

  !> The ellipse from (q0, M qdot0) over nsteps of h; variant 1/2: hand-derived L_d, 3/4: continuous
  !> midpoint; 2 and 4 with rtol = 1e-15.
  subroutine run_ellipse(variant, h, nsteps, q0, qd0, q, p, stat, msg)
    integer, intent(in) :: variant
    real(dp), intent(in) :: h, q0(3), qd0(3)
    integer(i8), intent(in) :: nsteps
    real(dp), intent(out) :: q(3), p(3)
    integer, intent(out) :: stat
    character(len=*), intent(out) :: msg
    type(ellipse_t), target :: md
    type(ellipse_lagrangian_t), target :: mc
    type(vci_integrator_t) :: integ
    real(dp) :: mm(3)
    md = ellipse_model(); mc = ellipse_lagrangian_model()
    mm = [md%inertia(), md%mass, md%mass]
    if (variant <= 2) then
      call integ%create(md, h, stat)
    else
      call integ%create(mc, h, stat)
      if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
    end if
    if (stat == VCI_OK) call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, stat)
    if (stat == VCI_OK .and. mod(variant, 2) == 0) call integ%set_tolerances(0.0_dp, 1.0e-15_dp, 30, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, mm * qd0, stat)
    if (stat == VCI_OK) call integ%integrate(nsteps, 1, stat)
    q = integ%configuration(); p = integ%momentum()
    msg = integ%message()
  end subroutine run_ellipse
end module roundoff_runs

program roundoff
  use vci_tool_args, only: arg_value
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_ref_ellipse, only: ellipse_params, ellipse_exact
  use vci_scene_ellipse, only: ellipse_t, ellipse_model
  use vci_scene_ellipse, only: ellipse_lagrangian_t, ellipse_lagrangian_model
  use roundoff_runs, only: run_ellipse
  implicit none
  real(dp), parameter :: hs(5) = [2.0e-2_dp, 1.0e-2_dp, 1.0e-3_dp, 1.0e-4_dp, 1.0e-5_dp]
  character(len=40), parameter :: vname(4) = [character(len=40) :: 'hand-derived L_d, rtol 1e-12', &
    'hand-derived L_d, rtol 1e-15', 'continuous L, midpoint, rtol 1e-12', 'continuous L, midpoint, rtol 1e-15']
  real(dp) :: q0(3), qd0(3), qe(3), qde(3), q(3), p(3), err(4), t_end, h
  real(dp), allocatable :: times(:)
  integer :: nimp, i, v, stat, nh
  integer(i8) :: nsteps
  character(len=256) :: msg, arg
  type(ellipse_params) :: par

  q0 = [acos(-1.0_dp) / 2.0_dp, 0.0_dp, 3.5_dp]; qd0 = [-3.0_dp, 2.0_dp, 0.0_dp]
  if (command_argument_count() >= 3) then
    call get_command_argument(1, arg)
    if (trim(arg) == '--long') then
      call arg_value(2, 'NSTEPS', nsteps)
      call arg_value(3, 'H', h)
      call get_command_argument(4, arg)
      call long_run(nsteps, h, trim(arg) == 'discrete')
      stop
    end if
  end if
  nh = 4
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    if (trim(arg) == '--with-1e-5') nh = 5
  end if
  t_end = 3.0_dp
  if (command_argument_count() >= 2) then     ! --t-end T
    call get_command_argument(1, arg)
    if (trim(arg) == '--t-end') then
      call arg_value(2, '--t-end', t_end)
    end if
  end if
  call ellipse_exact(par, q0, qd0, t_end, qe, qde, times, nimp)
  write (output_unit, '(a,f4.2,a,i0,a)') 'Ellipse from the exact momenta, Hamiltonian impacts, t = ', t_end, ' s (', nimp, &
    ' impacts); max |q - q_exact| (quad-precision event-driven reference):'
  write (output_unit, '(a)') ''
  write (output_unit, '(a)', advance='no') '| h | steps |'
  do v = 1, 4
    write (output_unit, '(1x,a," |")', advance='no') trim(vname(v))
  end do
  write (output_unit, '(a)') ''
  write (output_unit, '(a)') '|---:|---:|---:|---:|---:|---:|'
  do i = 1, nh
    nsteps = nint(t_end / hs(i), i8)
    do v = 1, 4
      call run_ellipse(v, hs(i), nsteps, q0, qd0, q, p, stat, msg)
      err(v) = maxval(abs(q - qe))
      if (stat /= VCI_OK) err(v) = -1.0_dp
    end do
    write (output_unit, '("| ",es7.1," | ",i0," | ",es8.2," | ",es8.2," | ",es8.2," | ",es8.2," |")') &
      hs(i), nsteps, err
  end do

contains

  !> H - H0 along a long run of the continuous ellipse (midpoint, Hamiltonian impacts): the largest
  !> |H - H0| up to t = 2^k h, k = 0, 1, ...
  subroutine long_run(nsteps, h, discrete)
    integer(i8), intent(in) :: nsteps
    real(dp), intent(in) :: h
    logical, intent(in) :: discrete
    type(vci_integrator_t) :: integ
    type(ellipse_t), target :: md
    real(dp) :: e0, e, emax, mm(3), lt(64), le(64), slope, eprev, de
    ! H's change over each step, apart for steps with and without impacts: count, sum, sum of squares
    real(dp) :: dsum(0:1), dsq(0:1)
    integer(i8) :: k, next, dn(0:1)
    type(vci_stats_t) :: st
    integer :: s, nfit, kind
    call long_setup(integ, h, e0, mm, md, discrete)
    nfit = 0
    emax = 0.0_dp; next = 1
    eprev = e0; dsum = 0.0_dp; dsq = 0.0_dp; dn = 0
    write (output_unit, '(a)') '| t | steps | max abs(H - H0) so far | impacts |'
    write (output_unit, '(a)') '|---:|---:|---:|---:|'
    do k = 1, nsteps
      call integ%step(1, s)
      if (s /= VCI_OK) then
        write (output_unit, '(a)') 'failed: '//integ%message(); return
      end if
      call md%energy(integ%configuration(), integ%momentum(), e, s)
      emax = max(emax, abs(e - e0))
      kind = min(1, integ%impact_count())
      de = e - eprev; eprev = e
      dn(kind) = dn(kind) + 1; dsum(kind) = dsum(kind) + de; dsq(kind) = dsq(kind) + de**2
      if (k == next .or. k == nsteps) then
        st = integ%statistics()
        write (output_unit, '("| ",es10.4," | ",i0," | ",es9.3," | ",i0," |")') real(k, dp) * h, k, emax, &
          st%impacts
        if (real(k, dp) * h >= 10.0_dp .and. emax > 0.0_dp .and. nfit < size(lt)) then
          nfit = nfit + 1; lt(nfit) = log(real(k, dp) * h); le(nfit) = log(emax)
        end if
        next = 2 * next
      end if
    end do
    if (nfit >= 2) then
      slope = sum((lt(1:nfit) - sum(lt(1:nfit)) / nfit) * (le(1:nfit) - sum(le(1:nfit)) / nfit)) / &
              sum((lt(1:nfit) - sum(lt(1:nfit)) / nfit)**2)
      write (output_unit, '(a)') ''
      write (output_unit, '(a,f5.2,a)') 'Least-squares slope of log max|H - H0| against log t for t >= 10 s: ', &
        slope, ' (Brouwer''s law: 0.5).'
    end if
    ! Unbiased changes add up like sqrt(count) * rms; a mean that is not zero adds count * mean.
    write (output_unit, '(a)') ''
    write (output_unit, '(a)') '| steps | count | mean of the change of H | rms of the change of H | count x mean '// &
      '| sqrt(count) x rms |'
    write (output_unit, '(a)') '|---|---:|---:|---:|---:|---:|'
    do kind = 0, 1
      if (dn(kind) == 0) cycle
      write (output_unit, '("| ",a," | ",i0," | ",es10.3," | ",es10.3," | ",es10.3," | ",es10.3," |")') &
        trim(merge('with an impact', 'regular       ', kind == 1)), dn(kind), dsum(kind) / real(dn(kind), dp), &
        sqrt(dsq(kind) / real(dn(kind), dp)), dsum(kind), sqrt(real(dn(kind), dp) * dsq(kind) / real(dn(kind), dp))
    end do
  end subroutine long_run

  subroutine long_setup(integ, h, e0, mm, md, discrete)
    type(vci_integrator_t), intent(inout) :: integ
    real(dp), intent(in) :: h
    logical, intent(in) :: discrete
    real(dp), intent(out) :: e0, mm(3)
    type(ellipse_t), target, intent(inout) :: md
    type(ellipse_lagrangian_t), target, save :: mc
    type(ellipse_t), target, save :: mdd
    integer :: s
    md = ellipse_model(); mdd = ellipse_model()
    mc = ellipse_lagrangian_model()
    mm = [md%inertia(), md%mass, md%mass]
    if (discrete) then
      call integ%create(mdd, h, s)
    else
      call integ%create(mc, h, s)
      call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, s)
    end if
    call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, s)
    call integ%init_from_momentum(0.0_dp, q0, mm * qd0, s)
    call md%energy(q0, mm * qd0, e0, s)
  end subroutine long_setup
end program roundoff
