!> A central force inside a circular wall centred on the centre: Kepler's L = |v|²/2 + 1/|q|
!> (vci_test_kepler's kepler_t, n = 2) with the wall g = R - |q| >= 0. The force and the wall's
!> normal are both along q, so the flow and an elastic reflection both conserve the angular
!> momentum q × p exactly: what a step changes of it is the scheme's round-off and solver
!> tolerance (issue 26 item 5).
module vci_test_central
  use vci
  use vci_test_kepler, only: kepler_t
  implicit none
  private

  type, extends(kepler_t), public :: central_disc_t
    real(dp) :: radius = 1.2_dp   !< the wall's radius
  contains
    procedure :: gaps, gap_gradients, energy
  end type central_disc_t

  public :: central_disc_model

contains

  function central_disc_model() result(model)
    type(central_disc_t) :: model
    model%n = 2
    model%n_gaps = 1
  end function central_disc_model

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
    e = 0.5_dp * sum(p**2) - 1.0_dp / norm2(q)
  end subroutine energy
end module vci_test_central
