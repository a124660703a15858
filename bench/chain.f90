!> Cost per step against n (issue 14, item 3): an FPU-beta chain of n unit masses between two fixed
!> ends, L = sum_i v_i^2/2 - sum_{i=0..n} [ (x_{i+1} - x_i)^2/2 + beta (x_{i+1} - x_i)^4/4 ],
!> x_0 = x_{n+1} = 0, with walls |x_i| <= w on every particle (2n gaps, far enough not to be hit in
!> the timed steps, so every step is a regular one with its gap test), analytic Hessians, midpoint
!> scheme. Prints the time per step against n, the time of one LU factorisation (dgetrf) of a dense
!> n x n matrix in the same process, their ratio, and the exponents fitted over n >= 32.
!> The chain is the scene's continuous model (examples/scenes/vci_scene_fpu_walls.f90) with w = 10.
!> Not a test: tools/bench/run_bench.sh runs it (OPENBLAS_NUM_THREADS decides LAPACK's threads).

program bench_chain_n
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_bench_stats, only: median
  use vci_lapack, only: dgetrf
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_t, fpu_walls_lagrangian_model
  implicit none
  integer, parameter :: ns(8) = [2, 4, 8, 16, 32, 64, 128, 256]
  type(fpu_walls_lagrangian_t), target :: model
  type(vci_integrator_t) :: integ
  integer, parameter :: nrep = 5
  integer :: in, n, stat, i, info, reps, rep
  integer(i8) :: nsteps, c0, c1, rate, it0, k0
  type(vci_stats_t) :: st
  real(dp) :: ts(nrep), tl(nrep)
  real(dp) :: tstep(size(ns)), tlu(size(ns)), its(size(ns)), slope_s, slope_l
  real(dp), allocatable :: q0(:), p0(:), a(:, :), a0(:, :)
  integer, allocatable :: ipiv(:)
  real(dp) :: pi
  pi = acos(-1.0_dp)
  write (output_unit, '(a)') '| n | unknowns | steps per repeat | us/step (median of 5) | Newton it./step '// &
    '| us per dgetrf (n x n) | step / dgetrf |'
  write (output_unit, '(a)') '|---:|---:|---:|---:|---:|---:|---:|'
  do in = 1, size(ns)
    n = ns(in)
    model = fpu_walls_lagrangian_model(n, 1.0_dp, 10.0_dp)   ! beta = 1, walls far away
    allocate (q0(n), p0(n))
    do i = 1, n                                  ! the lowest mode, amplitude 0.5: the quartic term matters
      q0(i) = 0.5_dp * sin(pi * real(i, dp) / real(n + 1, dp))
    end do
    p0 = 0.0_dp
    nsteps = max(400_i8, int(2.0e6_dp / real(n, dp)**2, i8))
    call integ%create(model, 0.05_dp, stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    call integ%integrate(5_i8, 1, stat)          ! warm-up (workspace, first factorisations)
    ! one LU of a dense n x n matrix like the Newton matrix (diagonally dominant), same process
    allocate (a(n, n), a0(n, n), ipiv(n))
    call random_number(a0); a0 = a0 - 0.5_dp
    do i = 1, n
      a0(i, i) = a0(i, i) + real(n, dp)
    end do
    reps = max(10, int(2.0e7_dp / real(n, dp)**3))
    st = integ%statistics(); it0 = st%newton_iterations; k0 = st%steps
    do rep = 1, nrep                             ! interleaved repeats; medians below
      call system_clock(c0, rate)
      call integ%integrate(nsteps, 1, stat)
      call system_clock(c1)
      st = integ%statistics()
      if (stat /= VCI_OK .or. st%impacts > 0) then
        write (output_unit, '(a)') 'chain run failed or hit a wall: '//integ%message(); stop 1
      end if
      ts(rep) = real(c1 - c0, dp) / real(rate, dp) / real(nsteps, dp)
      call system_clock(c0, rate)
      do i = 1, reps
        a = a0
        call dgetrf(n, n, a, n, ipiv, info)
      end do
      call system_clock(c1)
      tl(rep) = real(c1 - c0, dp) / real(rate, dp) / real(reps, dp)
    end do
    tstep(in) = median(ts); tlu(in) = median(tl)
    st = integ%statistics()
    its(in) = real(st%newton_iterations - it0, dp) / real(st%steps - k0, dp)
    write (output_unit, '("| ",i0," | ",i0," | ",i0," | ",f10.2," | ",f5.2," | ",f9.2," | ",f7.2," |")') &
      n, n, nsteps, 1.0e6_dp * tstep(in), its(in), 1.0e6_dp * tlu(in), tstep(in) / tlu(in)
    deallocate (q0, p0, a, a0, ipiv)
  end do
  slope_s = fit(real(ns(5:), dp), tstep(5:)); slope_l = fit(real(ns(5:), dp), tlu(5:))
  write (output_unit, '(a)') ''
  write (output_unit, '(a,f5.2,a,f5.2,a)') 'Fitted over n = 32 ... 256: time per step ~ n^', slope_s, &
    ', one dgetrf ~ n^', slope_l, '.'
contains
  real(dp) function fit(x, y)        ! least-squares slope of log y against log x
    real(dp), intent(in) :: x(:), y(:)
    real(dp) :: lx(size(x)), ly(size(x))
    lx = log(x); ly = log(y)
    fit = sum((lx - sum(lx) / size(lx)) * (ly - sum(ly) / size(ly))) / sum((lx - sum(lx) / size(lx))**2)
  end function fit
end program bench_chain_n
