!> Error against run time for vci on the paper's three scenes (issue 6 part 1, issue 7 item 3).
!>
!>   vci_results_driver reference FILE    exact data at the final times, for the Python peers
!>   vci_results_driver sweep FILE         step-size sweep, both impact conditions -> CSV
!>   vci_results_driver richardson FILE    pendulum reference vs Richardson extrapolation of vci
!>   vci_results_driver long DIR           ellipse, 10^6 steps at h = 1e-2: |E - E0| over time
!>
!> Timing: each timed repeat creates, initialises and runs an integrator with no observer; wall
!> time by system_clock (median over repeats), CPU time by cpu_time (median). Errors come from
!> one more, untimed, run with a recording observer. Measures: see vci_results_common.
!> The recording observer of the results driver.
module vci_results_recorder
  use vci
  use vci_results_common, only: mass, grav, pend_l, pend_f
  implicit none
  private
  public :: grow, energy_at

  !> Records impacts and the energy error of every state.
  type, public, extends(vci_observer_t) :: recorder_t
    class(vci_model_t), pointer :: model => null()
    logical :: reduced_pendulum_energy = .false.  !< pendulum: E from (theta, p_theta), see energy_at
    real(dp) :: e0 = 0.0_dp, emax = 0.0_dp
    real(dp), allocatable :: times(:)
    integer :: n_impacts = 0
    integer(i8) :: block = 0_i8           !< >0: keep the largest error of each block of steps
    real(dp) :: block_max = 0.0_dp
    real(dp), allocatable :: sample_t(:), sample_e(:)
    integer :: n_samples = 0
  contains
    procedure :: on_step => rec_step
    procedure :: on_impact => rec_impact
  end type recorder_t

contains

  subroutine rec_step(self, step, t, q, p, lambda, energy, stat)
    class(recorder_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    real(dp) :: e, err
    integer :: s
    e = energy_at(self, q, p)
    err = abs(e - self%e0)
    self%emax = max(self%emax, err)
    if (self%block > 0) then
      self%block_max = max(self%block_max, err)
      if (mod(step, self%block) == 0) then
        self%n_samples = self%n_samples + 1
        if (self%n_samples > size(self%sample_t)) then
          call grow(self%sample_t); call grow(self%sample_e)
        end if
        self%sample_t(self%n_samples) = t
        self%sample_e(self%n_samples) = self%block_max
        self%block_max = 0.0_dp
      end if
    end if
  end subroutine rec_step

  !> The energy of a state. For the pendulum, H(q, p) has p_phi^2 / sin^2(theta) and the run passes
  !> theta = pi, where the O(h) error of the discrete p_phi makes H meaningless; on the constraint
  !> phidot = f thetadot, so E = m l^2 (1 + f^2 sin^2 theta) thetadot^2 / 2 + m g l cos theta with
  !> thetadot = p_theta / (m l^2), the reduced energy the reference conserves.
  real(dp) function energy_at(self, q, p) result(e)
    class(recorder_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    integer :: s
    real(dp) :: thd
    if (self%reduced_pendulum_energy) then
      thd = p(1) / (mass * pend_l**2)
      e = 0.5_dp * mass * pend_l**2 * (1.0_dp + (pend_f(q(1)) * sin(q(1)))**2) * thd**2 + mass * grav * pend_l * cos(q(1))
    else
      s = 0
      call self%model%energy(q, p, e, s)
    end if
  end function energy_at

  subroutine rec_impact(self, impact, stat)
    class(recorder_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    self%n_impacts = self%n_impacts + 1
    if (self%n_impacts > size(self%times)) call grow(self%times)
    self%times(self%n_impacts) = impact%t
  end subroutine rec_impact

  subroutine grow(a)
    real(dp), allocatable, intent(inout) :: a(:)
    real(dp), allocatable :: tmp(:)
    allocate (tmp(2 * size(a)))
    tmp(:size(a)) = a
    call move_alloc(tmp, a)
  end subroutine grow
end module vci_results_recorder

program vci_results_driver
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  use vci
  use vci_scene_particle, only: particle_on_floor
  use vci_scene_ellipse, only: ellipse_model
  use vci_scene_pendulum, only: pendulum_model
  use vci_results_common
  use vci_results_recorder
  implicit none


  character(len=512) :: mode, target_path
  integer :: nargs

  nargs = command_argument_count()
  if (nargs < 2) then
    write (error_unit, '(a)') 'usage: vci_results_driver reference|sweep|richardson|long PATH'
    stop 2
  end if
  call get_command_argument(1, mode)
  call get_command_argument(2, target_path)
  select case (trim(mode))
  case ('reference'); call write_reference(trim(target_path))
  case ('sweep'); call sweep(trim(target_path))
  case ('richardson'); call richardson(trim(target_path))
  case ('long'); call long_run(trim(target_path))
  case default
    write (error_unit, '(a)') 'unknown mode '//trim(mode)
    stop 2
  end select

contains


  !> A fresh model of the scene.
  subroutine make_model(scene, model)
    integer, intent(in) :: scene
    class(vci_model_t), allocatable, intent(out) :: model
    select case (scene)
    case (SCENE_PARTICLE); allocate (model, source=particle_on_floor(mass, grav))
    case (SCENE_ELLIPSE); allocate (model, source=ellipse_model())
    case default; allocate (model, source=pendulum_model())
    end select
  end subroutine make_model

  !> Create and initialise an integrator with the scene's initial pair (the examples' set-ups).
  subroutine start(scene, model, h, impact_mode, integ, stat)
    integer, intent(in) :: scene, impact_mode
    class(vci_model_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    real(dp), allocatable :: q0(:), qd0(:)
    call initial_state(scene, q0, qd0)
    call integ%create(model, h, stat)
    if (stat == VCI_OK) call integ%set_tolerances(0.0_dp, 1.0e-12_dp, 30, stat)
    if (stat == VCI_OK) call integ%set_impact_energy(impact_mode, stat)
    if (stat /= VCI_OK) return
    if (scene == SCENE_PENDULUM) then
      call integ%init_from_pair(0.0_dp, q0, q0 + h * qd0, stat)
    else
      call integ%init_from_pair(-0.5_dp * h, q0 - 0.5_dp * h * qd0, q0 + 0.5_dp * h * qd0, stat)
    end if
  end subroutine start

  !> Steps after the initial pair so that the last grid time is the one nearest to t_end.
  integer(i8) function steps_to(scene, h, t_end)
    integer, intent(in) :: scene
    real(dp), intent(in) :: h, t_end
    if (scene == SCENE_PENDULUM) then
      steps_to = nint(t_end / h, i8) - 1_i8          ! grid t_k = k h, start at k = 1
    else
      steps_to = nint(t_end / h + 0.5_dp, i8) - 1_i8 ! grid t_k = (k - 1/2) h, start at k = 1
    end if
  end function steps_to

  character(len=16) function mode_name(impact_mode)
    integer, intent(in) :: impact_mode
    if (impact_mode == VCI_IMPACT_HAMILTONIAN) then
      mode_name = 'vci-hamiltonian'
    else
      mode_name = 'vci-discrete'
    end if
  end function mode_name

  !> One accuracy run and timed repeats; one CSV row.
  subroutine measure(unit, scene, h, impact_mode)
    integer, intent(in) :: unit, scene, impact_mode
    real(dp), intent(in) :: h
    class(vci_model_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(recorder_t) :: rec
    real(dp), allocatable :: qref(:), qdref(:), tref(:)
    real(dp) :: walls(9), cpus(9), w0, c0, e, err_final, err_impact
    integer(i8) :: nsteps
    integer :: stat, rstat, reps, r

    call make_model(scene, model)
    nsteps = steps_to(scene, h, t_final(scene))
    ! accuracy run, untimed
    call start(scene, model, h, impact_mode, integ, stat)
    rec%model => model
    rec%reduced_pendulum_energy = (scene == SCENE_PENDULUM)
    rec%e0 = exact_energy0(scene)
    allocate (rec%times(64), rec%sample_t(1), rec%sample_e(1))
    if (stat == VCI_OK) then
      e = energy_at(rec, integ%configuration(), integ%momentum())
      rec%emax = abs(e - rec%e0)
      call integ%integrate(nsteps, 1, stat, rec)
    end if
    if (stat /= VCI_OK) then
      write (error_unit, '(a,es9.2,a)') trim(scene_names(scene))//' h = ', h, ': '//integ%message()
      write (unit, '(a,",",a,",",es10.3,",",10(a,","),i0)') trim(scene_names(scene)), trim(mode_name(impact_mode)), &
        h, ('nan', r = 1, 10), stat
      return
    end if
    call reference_at(scene, integ%time(), qref, qdref, tref, rstat)
    err_final = maxval(abs(integ%configuration() - qref))
    err_impact = impact_time_error(tref, rec%times, rec%n_impacts)

    ! timed repeats: more of them for short runs
    reps = 0
    do r = 1, size(walls)
      w0 = wall_now(); c0 = cpu_now()
      call start(scene, model, h, impact_mode, integ, stat)
      call integ%integrate(nsteps, 1, stat)
      walls(r) = wall_now() - w0; cpus(r) = cpu_now() - c0
      reps = r
      if (r >= 3 .and. sum(walls(1:r)) > 1.0_dp) exit
      if (r >= 5 .and. sum(walls(1:r)) > 0.2_dp) exit
    end do
    write (unit, '(a,",",a,",",es10.3,",",es12.5,",",es12.5,",",i0,",",3(es12.5,","),i0,",",i0,",",i0,",",i0)') &
      trim(scene_names(scene)), trim(mode_name(impact_mode)), h, median(walls(1:reps)), median(cpus(1:reps)), reps, &
      err_final, rec%emax, err_impact, rec%n_impacts, size(tref), nsteps + 1_i8, stat
    flush (unit)
  end subroutine measure

  subroutine sweep(path)
    character(len=*), intent(in) :: path
    real(dp), parameter :: hs(11) = [2.0e-2_dp, 1.0e-2_dp, 5.0e-3_dp, 2.0e-3_dp, 1.0e-3_dp, 5.0e-4_dp, &
                                     2.0e-4_dp, 1.0e-4_dp, 5.0e-5_dp, 2.0e-5_dp, 1.0e-5_dp]
    integer :: unit, scene, i, imode
    integer, parameter :: modes(2) = [VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN]
    open (newunit=unit, file=path, status='replace', action='write')
    write (unit, '(a)') 'scene,method,param,wall_median,cpu_median,reps,err_final,err_energy,err_impact,' // &
      'n_impacts,n_ref_impacts,steps,status'
    do scene = 1, 3
      do imode = 1, 2
        do i = 1, size(hs)
          call measure(unit, scene, hs(i), modes(imode))
        end do
      end do
      write (output_unit, '(a)') 'vci sweep: '//trim(scene_names(scene))//' done'
      flush (output_unit)
    end do
    close (unit)
  end subroutine sweep

  !> Exact data at each scene's final time, for the Python peers (JSON).
  subroutine write_reference(path)
    character(len=*), intent(in) :: path
    integer :: unit, scene, rstat
    real(dp), allocatable :: q(:), qd(:), times(:)
    character(len=*), parameter :: fmt_arr = '(*(es25.17e3,:,","))'
    open (newunit=unit, file=path, status='replace', action='write')
    write (unit, '(a)') '{'
    do scene = 1, 3
      call reference_at(scene, t_final(scene), q, qd, times, rstat)
      write (unit, '(a)') '"'//trim(scene_names(scene))//'": {'
      write (unit, '(a,es25.17e3,a)') '"t_final": ', t_final(scene), ','
      write (unit, '(a,es25.17e3,a)') '"e0": ', exact_energy0(scene), ','
      write (unit, '(a,i0,a)') '"status": ', rstat, ','
      write (unit, '(a)', advance='no') '"q": ['
      write (unit, fmt_arr, advance='no') q
      write (unit, '(a)') '],'
      write (unit, '(a)', advance='no') '"qdot": ['
      write (unit, fmt_arr, advance='no') qd
      write (unit, '(a)') '],'
      write (unit, '(a)', advance='no') '"impact_times": ['
      if (size(times) > 0) write (unit, fmt_arr, advance='no') times
      write (unit, '(a)') ']'
      if (scene < 3) then
        write (unit, '(a)') '},'
      else
        write (unit, '(a)') '}'
      end if
    end do
    write (unit, '(a)') '}'
    close (unit)
  end subroutine write_reference

  !> The pendulum's paper L_d is first order: q(h) = q* + C h + O(h^2), so 2 q(h/2) - q(h) is an
  !> O(h^2) estimate of q* made by vci alone; it should approach the reduced-ODE reference.
  subroutine richardson(path)
    character(len=*), intent(in) :: path
    real(dp), parameter :: hs(7) = [4.0e-3_dp, 2.0e-3_dp, 1.0e-3_dp, 5.0e-4_dp, 2.5e-4_dp, 1.25e-4_dp, 6.25e-5_dp]
    class(vci_model_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(recorder_t) :: rec
    real(dp) :: q(2, size(hs)), ti(3, size(hs)), rq(2), rt(3)
    real(dp), allocatable :: qref(:), qdref(:), tref(:)
    integer :: i, stat, unit, rstat
    call make_model(SCENE_PENDULUM, model)
    call reference_at(SCENE_PENDULUM, t_final(SCENE_PENDULUM), qref, qdref, tref, rstat)
    do i = 1, size(hs)
      call start(SCENE_PENDULUM, model, hs(i), VCI_IMPACT_DISCRETE, integ, stat)
      rec = recorder_t()
      rec%model => model
      allocate (rec%times(64), rec%sample_t(1), rec%sample_e(1))
      call integ%integrate(steps_to(SCENE_PENDULUM, hs(i), t_final(SCENE_PENDULUM)), 1, stat, rec)
      if (stat /= VCI_OK .or. rec%n_impacts /= size(tref) .or. abs(integ%time() - t_final(SCENE_PENDULUM)) > 1.0e-9_dp) then
        write (error_unit, '(a,es10.3)') 'richardson: run failed or impact count differs at h = ', hs(i)
        stop 1
      end if
      q(:, i) = integ%configuration()
      ti(:, i) = rec%times(1:3)
    end do
    open (newunit=unit, file=path, status='replace', action='write')
    write (unit, '(a)') 'h,err_q_vci_h2,err_q_richardson,err_t_vci_h2,err_t_richardson,diff_q_richardson_vs_ref'
    do i = 1, size(hs) - 1
      rq = 2.0_dp * q(:, i + 1) - q(:, i)
      rt = 2.0_dp * ti(:, i + 1) - ti(:, i)
      write (unit, '(es10.3,5(",",es12.5))') hs(i), maxval(abs(q(:, i + 1) - qref)), maxval(abs(rq - qref)), &
        maxval(abs(ti(:, i + 1) - tref(1:3))), maxval(abs(rt - tref(1:3))), maxval(abs(rq - qref))
    end do
    close (unit)
  end subroutine richardson

  !> The ellipse over 10^4 s (10^6 steps at h = 1e-2), both impact conditions: |E - E0| over time
  !> (largest of each block of 100 steps) and the cost of the run without an observer.
  subroutine long_run(dir)
    character(len=*), intent(in) :: dir
    integer, parameter :: modes(2) = [VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN]
    integer(i8), parameter :: nsteps = 1000000_i8
    real(dp), parameter :: h = 1.0e-2_dp
    class(vci_model_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(recorder_t) :: rec
    real(dp) :: w0, c0, walls(3), cpus(3)
    integer :: imode, stat, unit, sunit, i, r
    call make_model(SCENE_ELLIPSE, model)
    open (newunit=sunit, file=dir//'/long_vci.csv', status='replace', action='write')
    write (sunit, '(a)') 'method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status'
    do imode = 1, 2
      do r = 1, 3
        w0 = wall_now(); c0 = cpu_now()
        call start(SCENE_ELLIPSE, model, h, modes(imode), integ, stat)
        call integ%integrate(nsteps - 1_i8, 1, stat)
        walls(r) = wall_now() - w0; cpus(r) = cpu_now() - c0
      end do
      rec = recorder_t()
      rec%model => model
      rec%block = 100_i8
      allocate (rec%times(1024), rec%sample_t(1024), rec%sample_e(1024))
      call start(SCENE_ELLIPSE, model, h, modes(imode), integ, stat)
      ! drift from the run's own first state (the initial pair's O(h^2) energy offset is not drift)
      rec%e0 = energy_at(rec, integ%configuration(), integ%momentum())
      call integ%integrate(nsteps - 1_i8, 1, stat, rec)
      if (stat /= VCI_OK) write (error_unit, '(a)') 'long run: '//integ%message()
      write (sunit, '(a,",",es10.3,",",es12.5,",",es12.5,",",es12.5,",",es12.5,",",i0,",",es14.7,",",i0)') &
        trim(mode_name(modes(imode))), h, median(walls), median(cpus), rec%emax, rec%sample_e(rec%n_samples), &
        rec%n_impacts, integ%time(), stat
      open (newunit=unit, file=dir//'/long_'//trim(mode_name(modes(imode)))//'.csv', status='replace', action='write')
      write (unit, '(a)') 't,energy_error'
      do i = 1, rec%n_samples
        write (unit, '(es14.7,",",es12.5)') rec%sample_t(i), rec%sample_e(i)
      end do
      close (unit)
      write (output_unit, '(a)') 'vci long run: '//trim(mode_name(modes(imode)))//' done'
      flush (output_unit)
    end do
    close (sunit)
  end subroutine long_run
end program vci_results_driver
