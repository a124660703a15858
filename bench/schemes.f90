!> Cost per step of the schemes built from a continuous Lagrangian, against the number of stages s
!> and the dimension n: a chain of n pendulums coupled by torsion springs,
!> L = sum_i (v_i^2/2 + 9.8 cos q_i) - sum_i k (1 - cos(q_{i+1} - q_i)), analytic Hessians, no walls.
!> Prints ns/step and the ratio to `midpoint` at the same n (ratios from one process; absolute
!> times depend on the machine). Not a test. Run: build/bin/vci_bench_schemes
module bench_chain
  use vci
  implicit none
  private
  type, extends(vci_lagrangian_t), public :: chain_t
    real(dp) :: k = 2.0_dp
  contains
    procedure :: lagrangian, dl_dq, dl_dv, hessians
  end type chain_t
contains
  subroutine lagrangian(self, q, v, l, stat)
    class(chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    integer :: i
    l = sum(0.5_dp * v**2 + 9.8_dp * cos(q))
    do i = 1, size(q) - 1
      l = l - self%k * (1.0_dp - cos(q(i + 1) - q(i)))
    end do
  end subroutine lagrangian
  subroutine dl_dq(self, q, v, out, stat)
    class(chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    integer :: i
    real(dp) :: f
    out = -9.8_dp * sin(q)
    do i = 1, size(q) - 1
      f = self%k * sin(q(i + 1) - q(i))
      out(i) = out(i) + f; out(i + 1) = out(i + 1) - f
    end do
  end subroutine dl_dq
  subroutine dl_dv(self, q, v, out, stat)
    class(chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = v
  end subroutine dl_dv
  subroutine hessians(self, q, v, lqq, lqv, lvv, stat)
    class(chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    integer :: i
    real(dp) :: c
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    do i = 1, size(q)
      lqq(i, i) = -9.8_dp * cos(q(i)); lvv(i, i) = 1.0_dp
    end do
    do i = 1, size(q) - 1
      c = self%k * cos(q(i + 1) - q(i))
      lqq(i, i) = lqq(i, i) - c; lqq(i + 1, i + 1) = lqq(i + 1, i + 1) - c
      lqq(i, i + 1) = lqq(i, i + 1) + c; lqq(i + 1, i) = lqq(i + 1, i) + c
    end do
  end subroutine hessians
end module bench_chain

program bench_schemes
  use vci
  use bench_chain
  implicit none
  integer, parameter :: ns(4) = [1, 4, 16, 32]
  type(chain_t), target :: model
  type(vci_integrator_t) :: integ
  integer :: in, ic, stat, n
  integer(i8) :: c0, c1, rate, nsteps
  real(dp) :: t, tmid
  character(len=12) :: label
  write (*, '(a)') '| n | scheme | ns/step | / midpoint |'
  write (*, '(a)') '|---|---|---|---|'
  do in = 1, size(ns)
    n = ns(in)
    model%n = n
    nsteps = max(200_i8, 400000_i8 / int(n * n, i8))
    do ic = 0, 5
      call integ%create(model, 1.0e-2_dp, stat)
      select case (ic)
      case (0); call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat); label = 'midpoint'
      case (1); call integ%set_scheme(VCI_SCHEME_LEFT, 1, stat); label = 'left'
      case default; call integ%set_scheme(VCI_SCHEME_LOBATTO, ic - 1, stat); write (label, '(a,i0)') 'lobatto ', ic - 1
      end select
      call integ%init_from_momentum(0.0_dp, spread(0.3_dp, 1, n), spread(1.0_dp, 1, n), stat)
      call system_clock(c0, rate)
      call integ%integrate(nsteps, 1, stat)
      call system_clock(c1)
      if (stat /= VCI_OK) then
        write (*, '(a)') integ%message(); stop 1
      end if
      t = 1.0e9_dp * real(c1 - c0, dp) / real(rate, dp) / real(nsteps, dp)
      if (ic == 0) tmid = t
      write (*, '(a,i0,a,a,a,f12.0,a,f8.2,a)') '| ', n, ' | ', trim(label), ' | ', t, ' | ', t / tmid, ' |'
    end do
  end do
end program bench_schemes
