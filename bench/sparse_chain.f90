!> Sparse against banded and dense Newton matrices (issue 28): the FPU-beta chain between walls
!> |x_i| <= 0.6 (examples/scenes/vci_scene_fpu_walls.f90) with long-range linear springs of
!> stiffness 0.5 between particles i and i + L, L = n / 8: each Hessian row has 5 nonzeros, but
!> the band that holds them has half-width L. Midpoint from L, the `hamiltonian` impact condition,
!> h = 0.01, from docs/RESULTS.md's chain start. Every step is timed on its own and classed as
!> regular or impact step (medians; each step's class on stderr). Arguments: dense | banded | sparse, the number of steps, then
!> the n to run. Not a test: docs/bench/sparse.md gives the command (OpenBLAS on one thread).
module bench_sparse_chain_model
  use vci, only: dp
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_t
  implicit none
  private
  !> The FPU chain plus springs (i, i + offset) of stiffness kl.
  type, extends(fpu_walls_lagrangian_t), public :: long_range_chain_t
    integer :: offset = 1
    real(dp) :: kl = 0.5_dp
  contains
    procedure :: lagrangian => lr_lagrangian, dl_dq => lr_dl_dq, hessians => lr_hessians, energy => lr_energy
  end type long_range_chain_t
contains
  real(dp) function lr_potential(self, q) result(v)
    class(long_range_chain_t), intent(in) :: self
    real(dp), intent(in) :: q(:)
    integer :: l, n
    n = size(q); l = self%offset
    v = 0.5_dp * self%kl * sum((q(1 + l:n) - q(1:n - l))**2)
  end function lr_potential
  subroutine lr_lagrangian(self, q, v, l, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    call self%fpu_walls_lagrangian_t%lagrangian(q, v, l, stat)
    l = l - lr_potential(self, q)
  end subroutine lr_lagrangian
  subroutine lr_energy(self, q, p, e, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    call self%fpu_walls_lagrangian_t%energy(q, p, e, stat)
    e = e + lr_potential(self, q)
  end subroutine lr_energy
  subroutine lr_dl_dq(self, q, v, out, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    integer :: i, l, n
    real(dp) :: d
    call self%fpu_walls_lagrangian_t%dl_dq(q, v, out, stat)
    n = size(q); l = self%offset
    do i = 1, n - l
      d = self%kl * (q(i + l) - q(i))
      out(i) = out(i) + d; out(i + l) = out(i + l) - d
    end do
  end subroutine lr_dl_dq
  subroutine lr_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(long_range_chain_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    integer :: i, l, n
    call self%fpu_walls_lagrangian_t%hessians(q, v, lqq, lqv, lvv, stat)
    n = size(q); l = self%offset
    do i = 1, n - l
      lqq(i, i) = lqq(i, i) - self%kl; lqq(i + l, i + l) = lqq(i + l, i + l) - self%kl
      lqq(i, i + l) = lqq(i, i + l) + self%kl; lqq(i + l, i) = lqq(i + l, i) + self%kl
    end do
  end subroutine lr_hessians
end module bench_sparse_chain_model

program bench_sparse_chain
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_bench_stats, only: median
  use, intrinsic :: iso_fortran_env, only: error_unit
  use bench_sparse_chain_model, only: long_range_chain_t
  implicit none
  type(long_range_chain_t), target :: model
  type(vci_integrator_t) :: integ
  integer :: n, stat, i, k, nsteps, nreg, nimp, ia, l, q
  integer(i8) :: c0, c1, rate
  type(vci_stats_t) :: st0, st1
  real(dp), allocatable :: q0(:), p0(:), treg(:), timp(:)
  integer, allocatable :: ns(:), colptr(:), rowind(:)
  real(dp) :: pi
  character(len=32) :: arg, mode
  real(dp), parameter :: h = 0.01_dp
  pi = acos(-1.0_dp)
  call get_command_argument(1, mode)
  call get_command_argument(2, arg); read (arg, *) nsteps
  allocate (ns(0))
  do ia = 3, command_argument_count()
    call get_command_argument(ia, arg); read (arg, *) k
    ns = [ns, k]
  end do
  do i = 1, size(ns)
    n = ns(i); l = max(2, n / 8)
    model%n = n; model%n_gaps = 2 * n; model%beta = 1.0_dp; model%w = 0.6_dp; model%offset = l
    allocate (q0(n), p0(n), treg(nsteps), timp(nsteps))
    do k = 1, n
      q0(k) = 0.24_dp * sin(2.0_dp * pi * real(k, dp) / real(n + 1, dp))
      p0(k) = 1.2_dp * sin(3.0_dp * pi * real(k, dp) / real(n + 1, dp)) + 0.8_dp * sin(pi * real(k, dp) / real(n + 1, dp))
    end do
    select case (trim(mode))
    case ('banded')
      call model%declare_bandwidth(l)
    case ('sparse')
      allocate (colptr(n + 1), rowind(2 * n))
      q = 0
      do k = 1, n                  ! the lower half: (k + 1, k) and (k + l, k)
        colptr(k) = q + 1
        if (k + 1 <= n) then
          q = q + 1; rowind(q) = k + 1
        end if
        if (k + l <= n) then
          q = q + 1; rowind(q) = k + l
        end if
      end do
      colptr(n + 1) = q + 1
      call model%declare_pattern(colptr, rowind)
      deallocate (colptr, rowind)
    end select
    call integ%create(model, h, stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
    if (stat == VCI_OK) call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, stat)
    if (stat == VCI_OK) call integ%set_max_impacts(max(16, 2 * n), stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    if (stat /= VCI_OK) then
      write (output_unit, '(a)') 'set-up failed: '//integ%message(); stop 1
    end if
    nreg = 0; nimp = 0
    do k = 1, nsteps
      st0 = integ%statistics()
      call system_clock(c0, rate)
      call integ%integrate(1_i8, 1, stat)
      call system_clock(c1)
      if (stat /= VCI_OK) then
        write (output_unit, '(a,i0,a)') 'n = ', n, ' failed: '//integ%message(); stop 1
      end if
      st1 = integ%statistics()
      write (error_unit, '(a,i0,a,i0,a,l1)') 'step ', n, ' ', k, ' impact ', st1%impacts > st0%impacts
      if (st1%impacts > st0%impacts) then
        nimp = nimp + 1; timp(nimp) = real(c1 - c0, dp) / real(rate, dp)
      else
        nreg = nreg + 1; treg(nreg) = real(c1 - c0, dp) / real(rate, dp)
      end if
    end do
    write (output_unit, '("| ",i0," | ",i0," | ",a," | ",i0," | ",i0," | ",i0," | ",f12.1," | ",f12.1," | ",es12.5," |")') &
      n, l, trim(mode), nsteps, nimp, st1%impacts, 1.0e6_dp * median(treg(1:nreg)), 1.0e6_dp * median(timp(1:nimp)), &
      sum(integ%configuration()**2)
    deallocate (q0, p0, treg, timp)
    call model%declare_bandwidth(-1)
    call model%declare_pattern([integer ::], [integer ::])
  end do
contains
end program bench_sparse_chain
