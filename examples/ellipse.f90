!> The paper's bouncing ellipse (docs/DESIGN.md §8): m = 1, g = 9.8, a = 1, b = 0.5, h = 1e-2,
!> q(0) = (pi/2, 0, 3.5), qdot(0) = (-3, 2, 0), 2 s. Start (--start): the pair q(0) -/+ (h/2) qdot(0)
!> (default of the hand-written L_d), or the exact (q(0), p(0) = dL/dqdot) (default with --scheme).
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
  continuous = ellipse_lagrangian_model()   ! also gives p(0) = dL/dqdot for --start exact
  if (allocated(opts%scheme)) then
    call run_example('ellipse', continuous, opts, init)
  else
    model = ellipse_model()
    model%analytic_hessian = opts%analytic_hessian
    model%fused_callback = .true.     ! D1, D2, D3 and the Hessian in one call (vci_model_t%ld_fused)
    call run_example('ellipse', model, opts, init)
  end if
contains
  subroutine init(integ, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    real(dp) :: q0(3), qd(3), p0(3), h
    h = integ%step_length()
    q0 = [acos(-1.0_dp) / 2.0_dp, 0.0_dp, 3.5_dp]
    qd = [-3.0_dp, 2.0_dp, 0.0_dp]
    if (opts%start == 'exact') then
      stat = 0
      call continuous%dl_dv(q0, qd, p0, stat)
      call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    else
      ! the pair brackets t = 0 by half a step: q(-h/2), q(h/2) to second order
      call integ%init_from_pair(-0.5_dp * h, q0 - 0.5_dp * h * qd, q0 + 0.5_dp * h * qd, stat)
    end if
  end subroutine init
end program ellipse
