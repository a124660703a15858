!> Where the ellipse's Hamiltonian-impact energy jumps come from: the run of test_stab_long
!> (paper's ellipse, h = 1e-2, start from the pair q0 -+ h qd0 / 2, VCI_IMPACT_HAMILTONIAN), one
!> line per step with impacts. H is exact in free flight (in exact arithmetic), so a step's change
!> of H splits into
!>   arrive: H(q_wall, p-) - H(start of the step)     (stage 1, sub-step alpha h)
!>   cond  : H(q_wall, p+) - H(q_wall, p-)            (the impact condition itself, summed over impacts)
!>   leave : H(end of the step) - H(q_wall, p+)       (the last sub-step, (1 - alpha) h)
!> and `jump` is what test_stab_long differences: H after this impact step - H after the last one
!> (jump - arrive - cond - leave: the regular steps in between). Then theta and x of the last wall
!> point. Usage: vci_impact_jumps [nsteps [file]]   (defaults 1e7, impact_jumps.txt); the table of
!> docs/IMPACT_ENERGY.md: tools/impact_energy/buckets.py file ... (one file per build compared).
program impact_jumps
  use vci
  use vci_scene_ellipse, only: ellipse_t, ellipse_model
  use vci_tool_args, only: arg_value, bad_argument
  implicit none
  real(dp), parameter :: h = 1.0e-2_dp, pi = acos(-1.0_dp)
  type(ellipse_t), target :: model
  type(vci_integrator_t) :: integ
  type(vci_impact_t) :: first, last
  real(dp) :: q0(3), qd(3), e_prev_step, e_prev_impact, e, e_arrive, e_minus_first, e_plus_last, cond, e_a, e_b
  integer(i8) :: k, nsteps
  integer :: stat, u, i, nimp
  character(len=256) :: arg, path
  nsteps = 10000000_i8; path = 'impact_jumps.txt'
  if (command_argument_count() >= 1) then
    call arg_value(1, 'NSTEPS', nsteps)
    call get_command_argument(1, arg)
    if (nsteps < 1) call bad_argument('NSTEPS', trim(arg), 'at least 1')
  end if
  if (command_argument_count() >= 2) call get_command_argument(2, path)
  model = ellipse_model()
  q0 = [pi / 2.0_dp, 0.0_dp, 3.5_dp]; qd = [-3.0_dp, 2.0_dp, 0.0_dp]
  call integ%create(model, h, stat)
  call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, stat)
  call integ%init_from_pair(0.0_dp, q0 - 0.5_dp * h * qd, q0 + 0.5_dp * h * qd, stat)
  call model%energy(integ%configuration(), integ%momentum(), e, stat)
  e_prev_step = e; e_prev_impact = e
  open (newunit=u, file=trim(path), status='replace', action='write')
  write (u, '(a)') '# step nimp alpha_first alpha_last arrive cond leave jump theta x'
  do k = 1, nsteps
    call integ%step(1, stat)
    if (stat /= VCI_OK) then
      print '(a,i0,a)', 'step ', k, ' failed: '//trim(integ%message()); exit
    end if
    call model%energy(integ%configuration(), integ%momentum(), e, stat)
    nimp = integ%impact_count()
    if (nimp > 0) then
      first = integ%impact(1); last = integ%impact(nimp)
      call model%energy(first%q, first%p_before, e_minus_first, stat)
      call model%energy(last%q, last%p_after, e_plus_last, stat)
      e_arrive = e_minus_first - e_prev_step
      cond = 0.0_dp
      do i = 1, nimp
        last = integ%impact(i)
        call model%energy(last%q, last%p_before, e_a, stat)
        call model%energy(last%q, last%p_after, e_b, stat)
        cond = cond + (e_b - e_a)
      end do
      write (u, '(i9,1x,i2,2(1x,es24.16),6(1x,es11.3))') k, nimp, first%alpha, last%alpha, e_arrive, cond, &
        e - e_plus_last, e - e_prev_impact, last%q(1), last%q(2)
      e_prev_impact = e
    end if
    e_prev_step = e
  end do
  close (u)
  print '(a,i0,a,es10.3)', 'steps: ', integ%step_index(), '  |H - H0| at the end: ', abs(e - e_prev_impact)
end program impact_jumps
