!> Where an impact step's time goes on a long chain (issue 28): the FPU-beta chain between walls
!> |x_i| <= 0.6 (examples/scenes/vci_scene_fpu_walls.f90, the continuous model with analytic
!> Hessians), midpoint from L, the `hamiltonian` impact condition, h = 0.01 over T = 2, from the
!> start of docs/RESULTS.md's chain (x_i = 0.24 sin(2 pi i/(n+1)), v_i = 1.2 sin(3 pi i/(n+1)) +
!> 0.8 sin(pi i/(n+1))). Every step is timed on its own and classed as regular (no impact) or impact
!> step; medians of each, their ratio, LU factorisations per step of each class, the peak resident
!> memory's growth over the run and at its end. Arguments: `banded` (declare the chain's bandwidth 1),
!> `bandcb` (that and the model's hessians_band: no n x n Hessian block), `whole`
!> (impact stages with the whole stage matrix factorised, set_bordered_impacts(.false.): the path
!> before bordering), `steps=K` (only the first K steps), `lobatto` (Lobatto IIIA-IIIB, 2 stages, instead of
!> the midpoint), `single` (a start where only the first mass meets a wall: x_i = 0.2 sin(2 pi
!> i/(n+1)), v_i = 0, then x_1 = 0.595, v_1 = 2: impact steps of one impact each, to compare one
!> impact with a regular step), `digest` (after each row, a line with the final state's bits folded into one
!> 64-bit word and the impact count: two builds whose arithmetic should agree compare it) and the
!> n to run (default 32 128 256). Not a test: tools/bench/run_chain.sh runs it with OpenBLAS on one thread.

program bench_chain_impacts
  use vci_tool_args, only: text_value
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_bench_stats, only: median
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_t, fpu_walls_lagrangian_model
  implicit none
  type(fpu_walls_lagrangian_t), target :: model
  type(vci_integrator_t) :: integ
  integer :: n, stat, i, k, nsteps, nreg, nimp, narg, ia, nn
  integer(i8) :: c0, c1, rate, f_reg, f_imp, imp_total, f0
  type(vci_stats_t) :: st0, st1
  real(dp), allocatable :: q0(:), p0(:), treg(:), timp(:)
  integer, allocatable :: ns(:)
  real(dp) :: pi, rss0, rss1
  logical :: banded, bandcb, whole, lobatto, digest, single
  integer :: max_steps
  character(len=32) :: arg
  real(dp), parameter :: h = 0.01_dp, t_end = 2.0_dp
  pi = acos(-1.0_dp)
  banded = .false.; bandcb = .false.; whole = .false.; lobatto = .false.; digest = .false.; single = .false.; max_steps = huge(1)
  narg = command_argument_count()
  allocate (ns(0)); nn = 0
  do ia = 1, narg
    call get_command_argument(ia, arg)
    if (trim(arg) == 'banded') then
      banded = .true.
    else if (trim(arg) == 'bandcb') then
      banded = .true.; bandcb = .true.
    else if (arg(1:6) == 'steps=') then
      call text_value(trim(arg(7:)), 'steps=', max_steps)
    else if (trim(arg) == 'whole') then
      whole = .true.
    else if (trim(arg) == 'lobatto') then
      lobatto = .true.
    else if (trim(arg) == 'digest') then
      digest = .true.
    else if (trim(arg) == 'single') then
      single = .true.
    else
      call text_value(trim(arg), 'N', k)
      ns = [ns, k]
    end if
  end do
  if (size(ns) == 0) ns = [32, 128, 256]
  write (output_unit, '(a)') '| n | band | steps | impact steps | impacts | regular step (us) | impact step (us) '// &
    '| impact / regular | LU per regular step | LU per impact step | memory growth (MB) | peak memory (MB) |'
  write (output_unit, '(a)') '|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|'
  do i = 1, size(ns)
    n = ns(i)
    model = fpu_walls_lagrangian_model(n, 1.0_dp, 0.6_dp)
    allocate (q0(n), p0(n))
    do k = 1, n
      q0(k) = 0.24_dp * sin(2.0_dp * pi * real(k, dp) / real(n + 1, dp))
      p0(k) = 1.2_dp * sin(3.0_dp * pi * real(k, dp) / real(n + 1, dp)) + 0.8_dp * sin(pi * real(k, dp) / real(n + 1, dp))
      if (single) then
        q0(k) = 0.2_dp * sin(2.0_dp * pi * real(k, dp) / real(n + 1, dp))
        p0(k) = 0.0_dp
      end if
    end do
    if (single) then
      q0(1) = 0.595_dp; p0(1) = 2.0_dp
    end if
    nsteps = min(nint(t_end / h), max_steps)
    allocate (treg(nsteps), timp(nsteps))
    rss0 = peak_rss_mb()
    if (banded) call model%declare_bandwidth(1)
    model%band_hessians = bandcb
    call integ%create(model, h, stat)
    if (stat == VCI_OK .and. lobatto) call integ%set_scheme(VCI_SCHEME_LOBATTO, 2, stat)
    if (stat == VCI_OK .and. .not. lobatto) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
    call integ%set_bordered_impacts(.not. whole)
    if (stat == VCI_OK) call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, stat)
    if (stat == VCI_OK) call integ%set_max_impacts(max(16, 2 * n), stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    if (stat /= VCI_OK) then
      write (output_unit, '(a)') 'set-up failed: '//integ%message(); stop 1
    end if
    nreg = 0; nimp = 0; f_reg = 0; f_imp = 0
    st0 = integ%statistics(); f0 = st0%factorisations
    do k = 1, nsteps
      st0 = integ%statistics()
      call system_clock(c0, rate)
      call integ%integrate(1_i8, 1, stat)
      call system_clock(c1)
      if (stat /= VCI_OK) then
        write (output_unit, '(a,i0,a)') 'chain n = ', n, ' failed: '//integ%message(); stop 1
      end if
      st1 = integ%statistics()
      if (st1%impacts > st0%impacts) then
        nimp = nimp + 1; timp(nimp) = real(c1 - c0, dp) / real(rate, dp)
        f_imp = f_imp + st1%factorisations - st0%factorisations
      else
        nreg = nreg + 1; treg(nreg) = real(c1 - c0, dp) / real(rate, dp)
        f_reg = f_reg + st1%factorisations - st0%factorisations
      end if
    end do
    rss1 = peak_rss_mb()
    imp_total = st1%impacts
    write (output_unit, '("| ",i0," | ",a," | ",i0," | ",i0," | ",i0," | ",f10.2," | ",f10.2," | ",f7.2," | ",f6.2,' // &
      '" | ",f6.2," | ",f7.1," | ",f7.1," |")') n, &
      trim(merge(merge('1, cb', '1    ', bandcb), 'dense', banded))//trim(merge(' whole', '      ', whole)), &
      nsteps, nimp, imp_total, &
      1.0e6_dp * median(treg(1:nreg)), 1.0e6_dp * median(timp(1:nimp)), median(timp(1:nimp)) / median(treg(1:nreg)), &
      real(f_reg, dp) / max(nreg, 1), real(f_imp, dp) / max(nimp, 1), rss1 - rss0, rss1
    if (digest) write (output_unit, '("digest n = ",i0,": ",z16.16,", impacts ",i0)') n, &
      fold_bits([integ%configuration(), integ%momentum()]), imp_total
    deallocate (q0, p0, treg, timp)
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

  !> Peak resident memory (VmHWM of /proc/self/status) in MB; 0 where that file is absent.
  real(dp) function peak_rss_mb()
    integer :: u, ios, kb
    character(len=128) :: line
    peak_rss_mb = 0.0_dp
    open (newunit=u, file='/proc/self/status', action='read', iostat=ios)
    if (ios /= 0) return
    do
      read (u, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (line(1:6) == 'VmHWM:') then
        read (line(7:), *) kb
        peak_rss_mb = real(kb, dp) / 1024.0_dp
      end if
    end do
    close (u)
  end function peak_rss_mb
end program bench_chain_impacts
