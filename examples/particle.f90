!> The bouncing particle: m = 1, g = 9.8, floor y = 0, start at (0, 1) with velocity (1, 0),
!> 3 s. Start (--start): the pair q(0) -/+ (h/2) qdot(0) (default of the hand-written L_d), or the exact
!> (q(0), p(0) = dL/dqdot) (default with --scheme).
program particle
  use vci
  use vci_scene_particle, only: particle_t, particle_on_floor, particle_lagrangian_t, particle_lagrangian_on_floor
  use vci_example_cli
  implicit none
  type(particle_t), target :: model
  type(particle_lagrangian_t), target :: continuous   ! with --scheme: L = m|v|^2/2 - m g y
  type(example_options_t) :: opts
  opts%h = 1.0e-2_dp; opts%t_final = 3.0_dp
  call parse_options(opts, 'particle', 'particle: a particle bouncing on the floor (defaults h = 1e-2, t-final = 3)')
  continuous = particle_lagrangian_on_floor(1.0_dp, 9.8_dp)   ! also gives p(0) for --start exact
  if (allocated(opts%scheme)) then
    call run_example('particle', continuous, opts, init)
  else
    model = particle_on_floor(1.0_dp, 9.8_dp)
    model%analytic_hessian = opts%analytic_hessian
    call run_example('particle', model, opts, init)
  end if
contains
  subroutine init(integ, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    real(dp) :: q0(2), qd(2), p0(2), h
    h = integ%step_length()
    q0 = [0.0_dp, 1.0_dp]; qd = [1.0_dp, 0.0_dp]
    if (opts%start == 'exact') then
      stat = 0
      call continuous%dl_dv(q0, qd, p0, stat)
      call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    else
      call integ%init_from_pair(-0.5_dp * h, q0 - 0.5_dp * h * qd, q0 + 0.5_dp * h * qd, stat)
    end if
  end subroutine init
end program particle
