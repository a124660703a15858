!> The Kepler billiard of issue 32: V = −1/|q|, M = I, inside the circle |q| <= R centred on the
!> centre of force (wall g = R − |q|, as vci_test_central's central_disc_t), as a separable model
!> for the explicit compositions, and its exact solution.
!>
!> Exact solution (closed form, no library): from pericentre on the orbit of vci_test_kepler
!> (a = 1, eccentricity e, period 2π, mean anomaly = t) the radius r = 1 − e cos E reaches R at
!> E_w = arccos((1 − R)/e), i.e. at t = M_w = E_w − e sin E_w and true anomaly f_w. An elastic
!> reflection off a wall normal to q flips the radial velocity only: energy and angular momentum
!> are kept, so the next flight is the same conic rotated by 2 f_w, run from E = −E_w to E_w
!> (duration 2 M_w). Flight k (k = 0 from the first impact) has its pericentre at angle 2 f_w (k+1).
module vci_test_kepler_billiard
  use vci
  use vci_test_kepler, only: kepler_exact
  implicit none
  private

  type, extends(vci_separable_t), public :: kepler_disc_sep_t
    real(dp) :: radius = 1.2_dp
  contains
    procedure :: potential, potential_gradient, potential_hessian, gaps, gap_gradients
  end type kepler_disc_sep_t

  public :: kepler_disc_sep_model, kepler_billiard_exact

contains

  !> M = I, wall radius R (default 1.2, as central_disc_t).
  function kepler_disc_sep_model(radius) result(model)
    real(dp), intent(in), optional :: radius
    type(kepler_disc_sep_t) :: model
    integer :: stat
    model%n = 2; model%n_gaps = 1
    if (present(radius)) model%radius = radius
    call model%set_mass_diagonal([1.0_dp, 1.0_dp], stat)
  end function kepler_disc_sep_model

  subroutine potential(self, q, v, stat)
    class(kepler_disc_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    v = -1.0_dp / norm2(q)
  end subroutine potential

  subroutine potential_gradient(self, q, dv, stat)
    class(kepler_disc_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    dv = q / norm2(q)**3
  end subroutine potential_gradient

  subroutine potential_hessian(self, q, hv, stat)
    class(kepler_disc_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: hv(:, :)
    integer, intent(inout) :: stat
    real(dp) :: r
    integer :: i
    r = norm2(q)
    do i = 1, 2
      hv(:, i) = -3.0_dp * q * q(i) / r**5
      hv(i, i) = hv(i, i) + 1.0_dp / r**3
    end do
  end subroutine potential_hessian

  subroutine gaps(self, q, g, stat)
    class(kepler_disc_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%radius - norm2(q)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(kepler_disc_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = -q / norm2(q)
  end subroutine gap_gradients

  !> The exact state (q, p) at time t of the billiard started at pericentre of the orbit of
  !> eccentricity e (a = 1; needs 1 − e < radius < 1 + e), and the impacts before t.
  subroutine kepler_billiard_exact(e, radius, t, q, p, n_impacts, times)
    real(dp), intent(in) :: e, radius, t
    real(dp), intent(out) :: q(2), p(2)
    integer, intent(out) :: n_impacts
    real(dp), allocatable, intent(out) :: times(:)
    real(dp) :: ew, mw, fw, flight, tk, angle, qs(2), ps(2)
    integer :: k
    ew = acos((1.0_dp - radius) / e)
    mw = ew - e * sin(ew)
    fw = 2.0_dp * atan(sqrt((1.0_dp + e) / (1.0_dp - e)) * tan(0.5_dp * ew))
    if (fw < 0.0_dp) fw = fw + 2.0_dp * acos(-1.0_dp)
    flight = 2.0_dp * mw
    if (t < mw) then
      n_impacts = 0
      allocate (times(0))
      call kepler_exact(e, t, q, p)
      return
    end if
    n_impacts = int((t - mw) / flight) + 1
    allocate (times(n_impacts))
    do k = 1, n_impacts
      times(k) = mw + (k - 1) * flight
    end do
    tk = times(n_impacts)
    call kepler_exact(e, -mw + (t - tk), qs, ps)
    angle = 2.0_dp * fw * n_impacts
    q = [cos(angle) * qs(1) - sin(angle) * qs(2), sin(angle) * qs(1) + cos(angle) * qs(2)]
    p = [cos(angle) * ps(1) - sin(angle) * ps(2), sin(angle) * ps(1) + cos(angle) * ps(2)]
  end subroutine kepler_billiard_exact
end module vci_test_kepler_billiard
