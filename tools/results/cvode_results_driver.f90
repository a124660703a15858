!> The peer SUNDIALS CVODE (Fortran 2003 interface) on the results scenes: the ODE of each scene in
!> first-order form, root finding on the gaps (decreasing crossings only; the walled pendulum has
!> two, the FPU chain 2n), and at each root the elastic impact map followed by CVodeReInit. Two variants a user would pick: Adams with the
!> fixed-point iteration (non-stiff) and BDF with Newton and a dense difference-quotient Jacobian.
!>
!>   cvode_results_driver sweep FILE [SCENE]  tolerance sweep rtol = atol = 1e-3 .. 1e-12 -> CSV
!>                                             (SCENE: that scene only, for run_results.sh --scene)
!>   cvode_results_driver long SCENE DIR RTOL [adams]  ellipse (1.1e5 s) or walled pendulum (6e4 s),
!>                                             >= 10^5 impacts: |E - E0| over time
!>
!> Timing and error measures as in vci_results_driver (see vci_results_common); the energy is
!> evaluated at every internal step, inside the timed loop (cheap next to a step).
module cvode_results_problem
  use, intrinsic :: iso_c_binding
  use fsundials_nvector_mod
  use fnvector_serial_mod
  use vci_results_common
  use results_scene_ode
  implicit none
  integer :: scene = SCENE_PARTICLE   !< the problem the callbacks evaluate
contains

  integer(c_int) function rhs_cb(t, sunvec_y, sunvec_f, user_data) result(ierr) bind(C)
    real(c_double), value :: t
    type(N_Vector) :: sunvec_y, sunvec_f
    type(c_ptr), value :: user_data
    real(c_double), pointer :: y(:), f(:)
    y => FN_VGetArrayPointer(sunvec_y)
    f => FN_VGetArrayPointer(sunvec_f)
    call scene_rhs(scene, y, f)
    ierr = 0
  end function rhs_cb

  integer(c_int) function root_cb(t, sunvec_y, gout, user_data) result(ierr) bind(C)
    real(c_double), value :: t
    type(N_Vector) :: sunvec_y
    real(c_double) :: gout(*)
    type(c_ptr), value :: user_data
    real(c_double), pointer :: y(:)
    y => FN_VGetArrayPointer(sunvec_y)
    call scene_gaps(scene, y, gout(1:n_roots(scene)))
    ierr = 0
  end function root_cb
end module cvode_results_problem

program cvode_results_driver
  use, intrinsic :: iso_c_binding
  use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
  use fcvode_mod
  use fsundials_context_mod
  use fsundials_nvector_mod
  use fnvector_serial_mod
  use fsundials_matrix_mod
  use fsundials_linearsolver_mod
  use fsundials_nonlinearsolver_mod
  use fsunmatrix_dense_mod
  use fsunlinsol_dense_mod
  use fsunnonlinsol_fixedpoint_mod
  use vci_results_common
  use cvode_results_problem
  implicit none

  !> What one run returns.
  type :: run_result_t
    real(c_double), allocatable :: y(:), times(:), sample_t(:), sample_e(:)
    real(c_double) :: emax = 0.0_c_double, t_end = 0.0_c_double
    real(c_double) :: cmax = 0.0_c_double   !< largest constraint residual (the nonholonomic pendulum)
    integer :: n_impacts = 0, n_samples = 0, status = 0
    integer(c_long) :: steps = 0
  end type run_result_t

  character(len=512) :: mode, path, arg, dir
  real(c_double) :: rtol_long

  if (command_argument_count() < 2) then
    write (error_unit, '(a)') 'usage: cvode_results_driver sweep FILE [SCENE] | long SCENE DIR RTOL [adams]'
    stop 2
  end if
  call get_command_argument(1, mode)
  call get_command_argument(2, path)
  select case (trim(mode))
  case ('sweep')
    arg = ''
    if (command_argument_count() >= 3) call get_command_argument(3, arg)
    call sweep(trim(path), scene_argument(arg))
  case ('long')
    call get_command_argument(3, dir)
    call get_command_argument(4, arg)
    read (arg, *) rtol_long
    arg = 'both'
    if (command_argument_count() >= 5) call get_command_argument(5, arg)
    call long_run(trim(path), trim(dir), rtol_long, trim(arg) == 'adams')
  case default
    write (error_unit, '(a)') 'unknown mode '//trim(mode)
    stop 2
  end select

contains

  !> Integrate the current scene from t = 0 to t_end at rtol = atol = tol with CVODE (Adams +
  !> fixed point when adams, else BDF + Newton/dense). sample_dt > 0: keep the largest |E - E0|
  !> of each window of that length.
  subroutine run_cvode(adams, tol, t_end, max_step, e0, res, sample_dt)
    logical, intent(in) :: adams
    real(c_double), intent(in) :: tol, t_end, max_step, e0
    type(run_result_t), intent(out) :: res
    real(c_double), intent(in), optional :: sample_dt
    type(c_ptr) :: ctx, mem
    type(N_Vector), pointer :: sv
    type(SUNMatrix), pointer :: amat
    type(SUNLinearSolver), pointer :: ls
    type(SUNNonlinearSolver), pointer :: nls
    real(c_double), allocatable, target :: y(:)
    real(rk), allocatable :: q0(:), qd0(:)
    real(c_double) :: tret(1), err, wmax, wend
    integer(c_int) :: ret
    integer(c_int), allocatable :: dirs(:), found(:)
    integer(c_long) :: nst(1)
    integer :: n, ns, nr

    n = state_size(scene)
    call initial_state(scene, q0, qd0)
    allocate (y(n))
    y(1:n / 2) = q0; y(n / 2 + 1:) = qd0
    allocate (res%times(64))
    ns = 1
    if (present(sample_dt)) ns = int(t_end / sample_dt) + 2
    allocate (res%sample_t(ns), res%sample_e(ns))
    ret = FSUNContext_Create(c_null_ptr, ctx)
    sv => FN_VMake_Serial(int(n, c_long), y, ctx)
    if (adams) then
      mem = FCVodeCreate(CV_ADAMS, ctx)
    else
      mem = FCVodeCreate(CV_BDF, ctx)
    end if
    ret = FCVodeInit(mem, c_funloc(rhs_cb), 0.0_c_double, sv)
    ret = FCVodeSStolerances(mem, tol, tol)
    ret = FCVodeSetMaxNumSteps(mem, 100000000_c_long)
    if (max_step > 0.0_c_double) ret = FCVodeSetMaxStep(mem, max_step)
    nr = n_roots(scene)
    allocate (dirs(nr), found(nr))
    ret = FCVodeRootInit(mem, int(nr, c_int), c_funloc(root_cb))
    dirs = -1
    ret = FCVodeSetRootDirection(mem, dirs)
    ret = FCVodeSetNoInactiveRootWarn(mem)
    nullify (amat, ls, nls)
    if (adams) then
      nls => FSUNNonlinSol_FixedPoint(sv, 0, ctx)
      ret = FCVodeSetNonlinearSolver(mem, nls)
    else
      amat => FSUNDenseMatrix(int(n, c_long), int(n, c_long), ctx)
      ls => FSUNLinSol_Dense(sv, amat, ctx)
      ret = FCVodeSetLinearSolver(mem, ls, amat)
    end if
    ret = FCVodeSetStopTime(mem, t_end)
    res%emax = abs(scene_energy(scene, y) - e0)
    res%cmax = abs(scene_constraint(scene, y))
    wmax = 0.0_c_double; wend = huge(1.0_c_double)
    if (present(sample_dt)) wend = sample_dt
    do
      ret = FCVode(mem, t_end, sv, tret(1), CV_ONE_STEP)
      if (ret < 0) then
        res%status = int(ret); exit
      end if
      err = abs(scene_energy(scene, y) - e0)
      res%emax = max(res%emax, err)
      res%cmax = max(res%cmax, abs(scene_constraint(scene, y)))
      if (present(sample_dt)) then
        do while (tret(1) > wend .and. res%n_samples < ns)
          res%n_samples = res%n_samples + 1
          res%sample_t(res%n_samples) = wend; res%sample_e(res%n_samples) = wmax
          wmax = 0.0_c_double; wend = wend + sample_dt
        end do
        wmax = max(wmax, err)
      end if
      if (ret == CV_ROOT_RETURN) then
        res%n_impacts = res%n_impacts + 1
        if (res%n_impacts > size(res%times)) call grow(res%times)
        res%times(res%n_impacts) = tret(1)
        ret = FCVodeGetRootInfo(mem, found)
        call scene_impact(scene, y, found)
        ret = FCVodeGetNumSteps(mem, nst)        ! counters restart with CVodeReInit
        res%steps = res%steps + nst(1)
        ret = FCVodeReInit(mem, tret(1), sv)
        ret = FCVodeSetStopTime(mem, t_end)
        cycle
      end if
      if (ret == CV_TSTOP_RETURN .or. tret(1) >= t_end) exit
    end do
    if (present(sample_dt) .and. res%n_samples < ns) then
      res%n_samples = res%n_samples + 1
      res%sample_t(res%n_samples) = tret(1); res%sample_e(res%n_samples) = wmax
    end if
    ret = FCVodeGetNumSteps(mem, nst)
    res%steps = res%steps + nst(1)
    res%y = y
    res%t_end = tret(1)
    call FCVodeFree(mem)
    if (associated(nls)) ret = FSUNNonlinSolFree(nls)
    if (associated(ls)) ret = FSUNLinSolFree(ls)
    if (associated(amat)) call FSUNMatDestroy(amat)
    call FN_VDestroy(sv)
    ret = FSUNContext_Free(ctx)
  end subroutine run_cvode

  subroutine grow(a)
    real(c_double), allocatable, intent(inout) :: a(:)
    real(c_double), allocatable :: tmp(:)
    allocate (tmp(2 * size(a)))
    tmp(:size(a)) = a
    call move_alloc(tmp, a)
  end subroutine grow

  !> Largest step allowed: the ellipse's flight is a polynomial, so an unbounded step could carry
  !> the body through a short dip of the gap (y - phi(theta) oscillates with the spin) unseen.
  real(c_double) function max_step_of(sc)
    integer, intent(in) :: sc
    max_step_of = merge(0.05_c_double, 0.0_c_double, sc == SCENE_ELLIPSE)
  end function max_step_of

  subroutine sweep(file, only_scene)
    character(len=*), intent(in) :: file
    character(len=*), intent(in) :: only_scene   !< a scene name, or empty for every scene
    integer :: unit, k, iv, r, reps, rstat, nq, isc
    type(run_result_t) :: res
    real(rk), allocatable :: qref(:), qdref(:), tref(:)
    real(c_double) :: tol, walls(MAX_REPEATS), cpus(MAX_REPEATS), w0, c0, e0, err_final, err_impact
    character(len=16) :: name
    open (newunit=unit, file=file, status='replace', action='write')
    write (unit, '(a)') 'scene,method,param,wall_median,cpu_median,reps,err_final,err_energy,err_impact,' // &
      'n_impacts,n_ref_impacts,steps,status,err_constraint'
    do isc = 1, N_SCENES
      if (len(only_scene) > 0 .and. only_scene /= trim(scene_names(isc))) cycle
      ! the module variable the callbacks read is set, not used as the DO variable: at -O3 a DO
      ! variable may live in a register while the loop runs, and the callbacks saw a stale scene
      scene = isc
      call reference_at(scene, t_final(scene), qref, qdref, tref, rstat)
      e0 = exact_energy0(scene)
      nq = state_size(scene) / 2
      ! BDF's dense 2n x 2n Newton matrix is not what a user runs on the large chain: Adams only
      do iv = 1, merge(1, 2, trim(scene_names(scene)) == LARGE_CHAIN_NAME)
        name = merge('cvode-adams', 'cvode-bdf  ', iv == 1)
        do k = 3, 13
          tol = 10.0_c_double**(-k)
          reps = 0
          do r = 1, size(walls)
            w0 = wall_now(); c0 = cpu_now()
            call run_cvode(iv == 1, tol, t_final(scene), max_step_of(scene), e0, res)
            walls(r) = wall_now() - w0; cpus(r) = cpu_now() - c0
            reps = r
            if (res%status /= 0) exit
            if (repeats_done(walls, r)) exit
          end do
          if (res%status /= 0) then
            write (unit, '(a,",",a,",",es10.3,",",9(a,","),i0,a)') trim(scene_names(scene)), trim(name), tol, &
              ('nan', r = 1, 9), res%status, ',nan'
            cycle
          end if
          err_final = maxval(abs(res%y(1:nq) - qref))
          err_impact = impact_time_error(tref, res%times, res%n_impacts)
          write (unit, '(a,",",a,",",es10.3,",",es12.5,",",es12.5,",",i0,",",3(es12.5,","),i0,",",i0,",",i0,",",i0,",",es12.5)') &
            trim(scene_names(scene)), trim(name), tol, median(walls(1:reps)), median(cpus(1:reps)), reps, &
            err_final, res%emax, err_impact, res%n_impacts, size(tref), res%steps, res%status, res%cmax
          flush (unit)
        end do
      end do
      write (output_unit, '(a)') 'cvode sweep: '//trim(scene_names(scene))//' done'
      flush (output_unit)
    end do
    close (unit)
  end subroutine sweep

  !> Long run (ellipse 1.1e5 s, walled pendulum 6e4 s; >= 10^5 impacts), both variants (or Adams
  !> only) at one tolerance: the largest |E - E0| of each 10 s window, and the cost (energy
  !> evaluated at every internal step, inside the timing).
  subroutine long_run(scene_name, dir, tol, adams_only)
    character(len=*), intent(in) :: scene_name, dir
    real(c_double), intent(in) :: tol
    logical, intent(in) :: adams_only
    type(run_result_t) :: res
    real(c_double) :: w0, c0, wall, cpu, t_end
    integer :: iv, unit, sunit, i
    character(len=16) :: name
    character(len=24) :: tag
    select case (scene_name)
    case ('ellipse'); scene = SCENE_ELLIPSE; t_end = 1.1e5_c_double
    case ('pendulum_walls'); scene = SCENE_PWALLS; t_end = 6.0e4_c_double
    case default
      write (error_unit, '(a)') 'long: scene must be ellipse or pendulum_walls'
      stop 2
    end select
    write (tag, '(es8.1)') tol
    open (newunit=sunit, file=dir//'/long_'//scene_name//'_cvode_'//trim(adjustl(tag))//'.csv', &
          status='replace', action='write')
    write (sunit, '(a)') 'scene,method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status'
    do iv = 1, merge(1, 2, adams_only)
      name = merge('cvode-adams', 'cvode-bdf  ', iv == 1)
      w0 = wall_now(); c0 = cpu_now()
      call run_cvode(iv == 1, tol, t_end, max_step_of(scene), exact_energy0(scene), res, 10.0_c_double)
      wall = wall_now() - w0; cpu = cpu_now() - c0
      write (sunit, '(a,",",a,",",es10.3,",",es12.5,",",es12.5,",",es12.5,",",es12.5,",",i0,",",es14.7,",",i0)') &
        scene_name, trim(name), tol, wall, cpu, res%emax, res%sample_e(res%n_samples), res%n_impacts, res%t_end, &
        res%status
      open (newunit=unit, file=dir//'/long_'//scene_name//'_'//trim(name)//'_'//trim(adjustl(tag))//'.csv', &
            status='replace', action='write')
      write (unit, '(a)') 't,energy_error'
      do i = 1, res%n_samples
        write (unit, '(es14.7,",",es12.5)') res%sample_t(i), res%sample_e(i)
      end do
      close (unit)
      write (output_unit, '(a,f7.1,a,i0,a)') 'cvode long run: '//scene_name//' '//trim(name)//' '// &
        trim(adjustl(tag))//' done (', cpu, ' s CPU, ', res%n_impacts, ' impacts)'
      flush (output_unit)
    end do
    close (sunit)
  end subroutine long_run
end program cvode_results_driver
