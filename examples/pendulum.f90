!> The paper's nonholonomic spherical pendulum in a cylinder (docs/DESIGN.md §8): m = 1, g = 9.8,
!> l = 2, R = 1.5, f = pi + cos^2 theta, h = 1e-3, q(0) = (0.75 pi, 0),
!> qdot(0) = (pi/4, (pi + 0.5) pi/4), 5 s. Start (--start): the paper's pair q0 = q(0), q1 = q(0) + h qdot(0)
!> (default of the hand-written L_d), or the exact (q(0), p(0) = dL/dqdot) (default with --scheme).
program pendulum
  use vci
  use vci_scene_pendulum, only: pendulum_t, pendulum_model, pendulum_lagrangian_t, pendulum_lagrangian_model
  use vci_example_cli
  implicit none
  type(pendulum_t), target :: model
  type(pendulum_lagrangian_t), target :: continuous   ! with --scheme: the same scene as L and Omega
  type(example_options_t) :: opts
  opts%h = 1.0e-3_dp; opts%t_final = 5.0_dp
  call parse_options(opts, 'pendulum', &
    'pendulum: the nonholonomic pendulum in a cylinder of the paper (defaults h = 1e-3, t-final = 5)')
  continuous = pendulum_lagrangian_model()   ! also gives p(0) = dL/dqdot for --start exact
  if (allocated(opts%scheme)) then
    call run_example('pendulum', continuous, opts, init)
  else
    model = pendulum_model()
    model%analytic_hessian = opts%analytic_hessian
    model%fused_callback = .true.     ! D1, D2, D3 and the Hessian in one call (vci_model_t%ld_fused)
    call run_example('pendulum', model, opts, init)
  end if
contains
  subroutine init(integ, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    real(dp) :: q0(2), qd(2), p0(2), pi
    pi = acos(-1.0_dp)
    q0 = [0.75_dp * pi, 0.0_dp]
    qd = [pi / 4.0_dp, (pi + 0.5_dp) * pi / 4.0_dp]
    if (opts%start == 'exact') then
      stat = 0
      call continuous%dl_dv(q0, qd, p0, stat)
      call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    else
      call integ%init_from_pair(0.0_dp, q0, q0 + integ%step_length() * qd, stat)
    end if
  end subroutine init
end program pendulum
