!> A central force inside a circular wall centred on the centre: L = |v|²/2 + k/|q| (n = 2), wall
!> g = R - |q| >= 0. The force and the wall's normal are both along q, so the flow and an elastic
!> reflection both conserve the angular momentum q × p exactly: what a step changes of it is the
!> scheme's round-off and solver tolerance (issue 26 item 5).
module vci_test_central
  use vci
  implicit none
  private

  type, extends(vci_lagrangian_t), public :: central_disc_t
    real(dp) :: k = 1.0_dp        !< strength of the attraction
    real(dp) :: radius = 1.2_dp   !< the wall's radius
  contains
    procedure :: lagrangian, dl_dq, dl_dv, hessians, gaps, gap_gradients, energy
  end type central_disc_t

  public :: central_disc_model

contains

  function central_disc_model() result(model)
    type(central_disc_t) :: model
    model%n = 2
    model%n_gaps = 1
  end function central_disc_model

  subroutine lagrangian(self, q, v, l, stat)
    class(central_disc_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * (v(1)**2 + v(2)**2) + self%k / norm2(q)
  end subroutine lagrangian

  subroutine dl_dq(self, q, v, out, stat)
    class(central_disc_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = (-self%k / norm2(q)**3) * q
  end subroutine dl_dq

  subroutine dl_dv(self, q, v, out, stat)
    class(central_disc_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = v
  end subroutine dl_dv

  subroutine hessians(self, q, v, lqq, lqv, lvv, stat)
    class(central_disc_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    real(dp) :: r
    integer :: i
    r = norm2(q)
    do i = 1, 2
      lqq(:, i) = (3.0_dp * self%k * q(i) / r**5) * q
      lqq(i, i) = lqq(i, i) - self%k / r**3
    end do
    lqv = 0.0_dp
    lvv = 0.0_dp; lvv(1, 1) = 1.0_dp; lvv(2, 2) = 1.0_dp
  end subroutine hessians

  subroutine gaps(self, q, g, stat)
    class(central_disc_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%radius - norm2(q)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(central_disc_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = -q / norm2(q)
  end subroutine gap_gradients

  subroutine energy(self, q, p, e, stat)
    class(central_disc_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * (p(1)**2 + p(2)**2) - self%k / norm2(q)
  end subroutine energy
end module vci_test_central
