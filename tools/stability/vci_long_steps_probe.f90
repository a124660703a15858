!> One step of a Kepler-below-the-wall run, taken again from its start as 1, 2, 4, 8 and 16 steps of
!> h / parts (lobatto, net off), against the closed form over h: the error per halving, the change
!> of H and each impact's condition and normal momenta. Usage (from the build directory):
!>
!>   bin/vci_long_steps_probe STAGES H Q1 Q2 P1 P2
!>
!> (the start as printed on a `full` line of vci_long_steps_trace 4 ...). Issue 27's analysis of
!> the Lobatto s = 2 rows below the wall (docs/STABILITY.md) reads it.
program vci_long_steps_probe
  use vci
  use vci_long_cases, only: kepler_wall_w
  use vci_kepler_wall, only: kepler_wall_t, kepler_wall_exact
  use vci_tool_args, only: arg_value, bad_argument
  implicit none
  type(kepler_wall_t), target :: model
  type(vci_integrator_t) :: integ
  type(vci_impact_t) :: imp
  real(dp) :: h, q0(2), p0(2), qe(2), pe(2), times(8), pmin, h0, err, errprev
  real(dp), allocatable :: q(:), p(:)
  integer :: stages, stat, parts, k, i, nimp, nall, level
  character(len=32) :: arg
  if (command_argument_count() < 6) then
    write (*, '(a)') 'usage: vci_long_steps_probe STAGES H Q1 Q2 P1 P2'
    stop 2
  end if
  call arg_value(1, 'STAGES', stages)
  call arg_value(2, 'H', h)
  call arg_value(3, 'Q1', q0(1)); call arg_value(4, 'Q2', q0(2))
  call arg_value(5, 'P1', p0(1)); call arg_value(6, 'P2', p0(2))
  call get_command_argument(2, arg)
  if (.not. (h > 0.0_dp)) call bad_argument('H', trim(arg), 'positive')
  model%n = 2; model%n_gaps = 1; model%w = kepler_wall_w
  h0 = 0.5_dp * sum(p0**2) - 1 / norm2(q0)
  call kepler_wall_exact(kepler_wall_w, q0, p0, h, qe, pe, nimp, times, pmin)
  write (*, '(a,i0,a,f7.4,a,es24.16)') 'closed form over h: ', nimp, ' impacts, smallest pericentre ', pmin, &
    ', H0 ', h0
  errprev = 0
  do level = 0, 4
    parts = 2**level
    call integ%create(model, h / parts, stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_LOBATTO, stages, stat)
    if (stat == VCI_OK) call integ%set_step_splits(1, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    nall = 0
    do k = 1, parts
      if (stat /= VCI_OK) exit
      call integ%step(1, stat)
      if (stat /= VCI_OK) exit
      do i = 1, integ%impact_count()
        imp = integ%impact(i); nall = nall + 1
        write (*, '(a,i3,a,f7.4,a,i0,a,2f9.4,a,f9.4,a,2es11.3)') '   part', k, ' alpha', imp%alpha, ' cond ', &
          imp%condition, ' p2-/p2+', imp%p_before(2), imp%p_after(2), ' H(q,p+)-H0', &
          0.5_dp * sum(imp%p_after**2) - 1 / norm2(imp%q) - h0, ' E-/E+', imp%energy_before, imp%energy_after
      end do
    end do
    if (stat /= VCI_OK) then
      write (*, '(a,i0,a,i0,a,a)') 'parts ', parts, ': status ', stat, ' ', trim(integ%message()); cycle
    end if
    q = integ%configuration(); p = integ%momentum()
    err = max(maxval(abs(q - qe)), maxval(abs(p - pe)))
    write (*, '(a,i3,a,es10.3,a,es10.2,a,i0,a,f8.1)') 'parts ', parts, ': error ', err, ', H - H0 ', &
      0.5_dp * sum(p**2) - 1 / norm2(q) - h0, ', impacts ', nall, ', ratio ', errprev / err
    errprev = err
  end do
end program vci_long_steps_probe
