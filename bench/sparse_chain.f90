!> Sparse against banded and dense Newton matrices (issue 28): the FPU-beta chain between walls
!> |x_i| <= 0.6 with long-range linear springs of stiffness 0.5 between particles i and i + L,
!> L = n / 8 (examples/scenes/vci_scene_long_range_chain.f90): each Hessian row has 5 nonzeros, but
!> the band that holds them has half-width L. Midpoint from L, the `hamiltonian` impact condition,
!> h = 0.01, from docs/RESULTS.md's chain start. Every step is timed on its own and classed as
!> regular or impact step (medians; each step's class on stderr). Arguments: dense | banded |
!> sparse (the pattern, dense Hessian callback) | sparsecb (the pattern and hessians_sparse alone),
!> the number of steps, then the n to run (and `digest`: after each row, a line with the final
!> state's bits folded into one 64-bit word, which two builds whose arithmetic should agree compare).
!> The last column is the peak resident memory (kB).
!> Not a test: docs/bench/sparse.md gives the command (OpenBLAS on one thread).
program bench_sparse_chain
  use vci_tool_args, only: arg_value, text_value
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_bench_stats, only: median
  use, intrinsic :: iso_fortran_env, only: error_unit
  use vci_scene_long_range_chain, only: long_range_chain_t
  implicit none
  type(long_range_chain_t), target :: model
  type(vci_integrator_t) :: integ
  integer :: n, stat, i, k, nsteps, nreg, nimp, ia, l
  integer(i8) :: c0, c1, rate
  type(vci_stats_t) :: st0, st1
  real(dp), allocatable :: q0(:), p0(:), treg(:), timp(:)
  integer, allocatable :: ns(:)
  real(dp) :: pi
  logical :: digest
  character(len=32) :: arg, mode
  real(dp), parameter :: h = 0.01_dp
  pi = acos(-1.0_dp)
  call get_command_argument(1, mode)
  call arg_value(2, 'NSTEPS', nsteps)
  allocate (ns(0))
  digest = .false.
  do ia = 3, command_argument_count()
    call get_command_argument(ia, arg)
    if (trim(arg) == 'digest') then
      digest = .true.; cycle
    end if
    call text_value(trim(arg), 'N', k)
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
    case ('sparse')              ! the pattern, Hessians gathered from the dense callback (O(n^2))
      model%sparse_hessians = .false.; model%dense_hessians = .true.
      call model%declare_long_range_pattern(.false.)
    case ('sparsecb')            ! the pattern and the sparse Hessian callback alone (O(nnz))
      model%sparse_hessians = .true.; model%dense_hessians = .false.
      call model%declare_long_range_pattern(.false.)
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
    write (output_unit, '("| ",i0," | ",i0," | ",a," | ",i0," | ",i0," | ",i0," | ",f12.1," | ",f12.1," | ",es12.5, &
                        &" | ",i0," |")') &
      n, l, trim(mode), nsteps, nimp, st1%impacts, 1.0e6_dp * median(treg(1:nreg)), 1.0e6_dp * median(timp(1:nimp)), &
      sum(integ%configuration()**2), peak_kb()
    if (digest) write (output_unit, '("digest n = ",i0,": ",z16.16,", impacts ",i0)') n, &
      fold_bits([integ%configuration(), integ%momentum()]), st1%impacts
    deallocate (q0, p0, treg, timp)
    call model%declare_bandwidth(-1)
    call model%declare_pattern([integer ::], [integer ::])
  end do
contains
  !> The bits of x folded into one word (rotate and exclusive or): any changed bit changes it.
  integer(i8) function fold_bits(x)
    real(dp), intent(in) :: x(:)
    integer :: j
    fold_bits = 0_i8
    do j = 1, size(x)
      fold_bits = ieor(ishftc(fold_bits, 7), transfer(x(j), 0_i8))
    end do
  end function fold_bits

  !> The process's peak resident memory so far (VmHWM of /proc/self/status, kB; 0 if unreadable).
  integer function peak_kb()
    integer :: u, ios
    character(len=128) :: line
    peak_kb = 0
    open (newunit=u, file='/proc/self/status', action='read', iostat=ios)
    if (ios /= 0) return
    do
      read (u, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (line(1:6) == 'VmHWM:') read (line(7:), *, iostat=ios) peak_kb
    end do
    close (u)
  end function peak_kb
end program bench_sparse_chain
