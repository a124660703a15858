!> A pendulum swinging between two walls at +-1 rad (an impact oscillator with nonlinear free
!> flight): theta'' = -(g/l) sin theta, g/l = 9.8, theta(0) = 0, theta'(0) = 4 (p0 = 4), elastic
!> walls; 18 impacts in 10 s. A continuous model discretised by --scheme (default lobatto, --stages 4;
!> --scheme composition --order p runs the explicit compositions on its separable form);
!> prints the errors of the final state and of the impact times against an exact reference
!> (quadrature of t(theta), vci_ref_pendulum_quad).
program pendulum_walls
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  use vci
  use vci_scene_pendulum_walls, only: pendulum_walls_t, pendulum_walls_model
  use vci_scene_pendulum_walls_sep, only: pendulum_walls_sep_t, pendulum_walls_sep_model
  use vci_ref_pendulum_quad, only: pendulum_quad_t, pendulum_quad_state, pendulum_quad_impacts
  use vci_example_cli
  implicit none
  type(pendulum_walls_t), target :: model
  type(pendulum_walls_sep_t), target :: separable   ! the same scene for --scheme composition
  type(vci_integrator_t) :: integ
  type(example_options_t) :: opts
  type(pendulum_quad_t) :: ref
  real(dp), allocatable :: times(:), found(:)
  real(dp) :: th, om, terr
  real(dp), allocatable :: q(:), p(:)
  type(vci_impact_t) :: imp
  type(vci_stats_t) :: stats
  integer :: stat, nex, nimp, j, used_energy
  integer(i8) :: nsteps, k
  opts%h = 5.0e-2_dp; opts%t_final = 10.0_dp
  opts%scheme = 'lobatto'; opts%stages = 4; opts%rtol = 1.0e-15_dp
  call parse_options(opts, 'pendulum_walls', 'pendulum_walls: a pendulum between walls at +-1 rad, against its '// &
    'exact solution (defaults h = 5e-2, t-final = 10, --scheme lobatto --stages 4, --rtol 1e-15)')
  ! this example compares with its exact solution only: it has no trajectory file and runs forward
  if (allocated(opts%output) .or. allocated(opts%from) .or. opts%backward .or. opts%every > 0 .or. opts%compress > 0) then
    write (error_unit, '(a)') 'pendulum_walls: --output, --from, --backward, --every and --compress are not supported here '// &
      '(this example writes no trajectory and runs forward)'
    stop 1, quiet=.true.
  end if
  if (opts%t_final < 0.0_dp) then
    write (error_unit, '(a)') 'pendulum_walls: --t-final must be >= 0'
    stop 1, quiet=.true.
  end if
  if (opts%scheme == 'composition') then
    separable = pendulum_walls_sep_model(.true.)
    call create_integrator('pendulum_walls', separable, opts, integ)
  else
    model = pendulum_walls_model(.true.)
    call create_integrator('pendulum_walls', model, opts, integ)
  end if
  call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
  if (stat == VCI_OK .and. opts%check_model) call check_model_at_start('pendulum_walls', model, integ, opts%h)
  if (stat == VCI_OK .and. opts%impact_energy /= VCI_IMPACT_DISCRETE) call integ%set_impact_energy(opts%impact_energy, stat)
  if (stat /= VCI_OK) then
    write (output_unit, '(a)') 'pendulum_walls: '//integ%message()
    stop 2
  end if
  nsteps = steps_to('pendulum_walls', 0.0_dp, opts%t_final, opts%h, 1)
  ref%k = 9.8_dp; ref%theta_wall = 1.0_dp; ref%theta0 = 0.0_dp; ref%omega0 = 4.0_dp
  call pendulum_quad_impacts(ref, real(nsteps, dp) * opts%h, times, nex)
  allocate (found(nex + 64))
  nimp = 0
  do k = 1, nsteps
    call integ%step(1, stat)
    if (stat /= VCI_OK) exit
    do j = 1, integ%impact_count()
      nimp = nimp + 1
      imp = integ%impact(j)
      if (nimp <= size(found)) found(nimp) = imp%t
    end do
  end do
  used_energy = opts%impact_energy
  ! what was used: a composition has an order, not stages, and its impacts always use H
  if (integ%scheme() == VCI_SCHEME_COMPOSITION) used_energy = VCI_IMPACT_HAMILTONIAN
  write (output_unit, '(a,i0,a,es10.3,a,i0,a,a)') 'scheme: '//trim(vci_scheme_name(integ%scheme()))// &
    trim(merge('   order: ', '   stages:', integ%scheme() == VCI_SCHEME_COMPOSITION))//' ', &
    integ%stages(), '   h = ', opts%h, '   steps: ', nsteps, '   impact energy: ', &
    trim(merge('hamiltonian', 'discrete   ', used_energy == VCI_IMPACT_HAMILTONIAN))
  if (stat /= VCI_OK) then
    write (output_unit, '(a)') 'status: '//vci_status_name(stat)//': '//integ%message()
    stop 2
  end if
  call pendulum_quad_state(ref, integ%time(), th, om)
  write (output_unit, '(a,i0,a,i0)') 'impacts: ', nimp, '   exact: ', nex
  q = integ%configuration(); p = integ%momentum()
  write (output_unit, '(a,es24.16,a,es24.16)') 'end state: t = ', integ%time(), '  theta = ', q(1)
  write (output_unit, '(a,es10.3,a,es10.3)') 'error against the exact solution: theta ', abs(q(1) - th), &
    '   theta'' ', abs(p(1) - om)
  if (nimp == nex) then
    terr = 0.0_dp
    if (nex > 0) terr = maxval(abs(found(1:nex) - times(1:nex)))
    write (output_unit, '(a,es10.3)') 'impact times: max error ', terr
  end if
  stats = integ%statistics()
  write (output_unit, '(a,i0,a,i0)') 'newton: solves ', stats%newton_solves, '  iterations ', &
    stats%newton_iterations
  call print_split_steps(integ)
  write (output_unit, '(a)') 'status: ok'
  deallocate (times, found, q, p)   ! a main program's allocatables are not freed at its end (valgrind)
end program pendulum_walls
