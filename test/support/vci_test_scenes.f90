!> Starting the paper's scenes the way the examples do, for tests.
module vci_test_scenes
  use vci
  implicit none
  private
  public :: start_particle, start_ellipse, start_pendulum, pi, ellipse_q0, ellipse_qdot0

  real(dp), parameter :: pi = acos(-1.0_dp)
  real(dp), parameter :: ellipse_q0(3) = [pi / 2.0_dp, 0.0_dp, 3.5_dp]
  real(dp), parameter :: ellipse_qdot0(3) = [-3.0_dp, 2.0_dp, 0.0_dp]

contains

  !> Midpoint pair q(0) -/+ (h/2) qdot(0) at t0 = -h/2: the current state is index 1 at t = h/2.
  subroutine start_particle(integ, model, h, q0, qdot0, stat)
    type(vci_integrator_t), intent(inout) :: integ
    class(vci_model_t), target, intent(inout) :: model
    real(dp), intent(in) :: h, q0(:), qdot0(:)
    integer, intent(out) :: stat
    call integ%create(model, h, stat)
    if (stat /= VCI_OK) return
    call integ%init_from_pair(-0.5_dp * h, q0 - 0.5_dp * h * qdot0, q0 + 0.5_dp * h * qdot0, stat)
  end subroutine start_particle

  subroutine start_ellipse(integ, model, h, stat)
    type(vci_integrator_t), intent(inout) :: integ
    class(vci_model_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    integer, intent(out) :: stat
    call start_particle(integ, model, h, ellipse_q0, ellipse_qdot0, stat)
  end subroutine start_ellipse

  !> The paper's pair q0 = q(0), q1 = q(0) + h qdot(0) at t0 = 0.
  subroutine start_pendulum(integ, model, h, stat)
    type(vci_integrator_t), intent(inout) :: integ
    class(vci_model_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    integer, intent(out) :: stat
    real(dp) :: q0(2), qd(2)
    q0 = [0.75_dp * pi, 0.0_dp]
    qd = [pi / 4.0_dp, (pi + 0.5_dp) * pi / 4.0_dp]
    call integ%create(model, h, stat)
    if (stat /= VCI_OK) return
    call integ%init_from_pair(0.0_dp, q0, q0 + h * qd, stat)
  end subroutine start_pendulum
end module vci_test_scenes
