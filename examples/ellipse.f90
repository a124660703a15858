!> The paper's bouncing ellipse (docs/DESIGN.md §8): m = 1, g = 9.8, a = 1, b = 0.5, h = 1e-2,
!> q(0) = (pi/2, 0, 3.5), qdot(0) = (-3, 2, 0), initial pair q(0) -/+ (h/2) qdot(0), 2 s.
program ellipse
  use vci
  use vci_scene_ellipse, only: ellipse_t, ellipse_model, ellipse_lagrangian_t, ellipse_lagrangian_model
  use vci_example_cli
  implicit none
  type(ellipse_t), target :: model
  type(ellipse_lagrangian_t), target :: continuous   ! with --scheme
  type(example_options_t) :: opts
  opts%h = 1.0e-2_dp; opts%t_final = 2.0_dp
  call parse_options(opts, 'ellipse', 'ellipse: the bouncing ellipse of the paper (defaults h = 1e-2, t-final = 2)')
  if (allocated(opts%scheme)) then
    continuous = ellipse_lagrangian_model()
    call run_example('ellipse', continuous, opts, init)
  else
    model = ellipse_model()
    model%analytic_hessian = opts%analytic_hessian
    call run_example('ellipse', model, opts, init)
  end if
contains
  subroutine init(integ, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    real(dp) :: q0(3), qd(3), h
    h = integ%step_length()
    q0 = [acos(-1.0_dp) / 2.0_dp, 0.0_dp, 3.5_dp]
    qd = [-3.0_dp, 2.0_dp, 0.0_dp]
    ! the pair brackets t = 0 by half a step: q(-h/2), q(h/2) to second order
    call integ%init_from_pair(-0.5_dp * h, q0 - 0.5_dp * h * qd, q0 + 0.5_dp * h * qd, stat)
  end subroutine init
end program ellipse
