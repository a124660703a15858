!> The walled pendulum of vci_scene_pendulum_walls as a separable model (vci_separable_t):
!> M = m l², V(θ) = −m g l cos θ, walls at ±θ_w. The explicit compositions (VCI_SCHEME_COMPOSITION)
!> need this kind; the implicit schemes run it as well (L, ∂L/∂q, ∂L/∂qdot, H are derived from M, V).
module vci_scene_pendulum_walls_sep
  use vci, only: dp, vci_separable_t
  use vci_scene_pendulum_walls, only: pendulum_walls_gaps, pendulum_walls_gap_gradients
  implicit none
  private

  type, extends(vci_separable_t), public :: pendulum_walls_sep_t
    real(dp) :: mass_ = 1.0_dp, grav = 9.8_dp, length = 1.0_dp, theta_wall = 1.0_dp
  contains
    procedure :: potential, potential_gradient, potential_hessian, gaps, gap_gradients
  end type pendulum_walls_sep_t

  public :: pendulum_walls_sep_model

contains

  !> Defaults: m = 1, g = 9.8, l = 1, walls at ±1 rad (walls = .false.: no walls).
  function pendulum_walls_sep_model(walls) result(model)
    logical, intent(in) :: walls
    type(pendulum_walls_sep_t) :: model
    integer :: stat
    model%n = 1
    model%n_gaps = merge(2, 0, walls)
    call model%set_mass_diagonal([model%mass_ * model%length**2], stat)
  end function pendulum_walls_sep_model

  subroutine potential(self, q, v, stat)
    class(pendulum_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    v = -self%mass_ * self%grav * self%length * cos(q(1))
  end subroutine potential

  subroutine potential_gradient(self, q, dv, stat)
    class(pendulum_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    dv(1) = self%mass_ * self%grav * self%length * sin(q(1))
  end subroutine potential_gradient

  subroutine potential_hessian(self, q, hv, stat)
    class(pendulum_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: hv(:, :)
    integer, intent(inout) :: stat
    hv(1, 1) = self%mass_ * self%grav * self%length * cos(q(1))
  end subroutine potential_hessian

  subroutine gaps(self, q, g, stat)
    class(pendulum_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    call pendulum_walls_gaps(self%theta_wall, q, g)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(pendulum_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    call pendulum_walls_gap_gradients(dg)
  end subroutine gap_gradients
end module vci_scene_pendulum_walls_sep
