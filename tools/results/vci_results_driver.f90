!> Error against run time for vci on the results scenes (issues 6, 7, 16): the paper's three, the
!> walled planar pendulum and the FPU-beta chain between walls.
!>
!>   vci_results_driver reference FILE    exact data at the final times, for the Python peers
!>   vci_results_driver sweep FILE [PREFIX [SCENE]]  step-size sweep of every variant -> CSV
!>                                         (PREFIX, SCENE: only the rows whose label starts so)
!>   vci_results_driver richardson FILE    pendulum reference vs Richardson extrapolation of vci
!>   vci_results_driver once SCENE LABEL H one untimed run of one row (for callgrind: run_once is
!>                                         inlined at -O3; count the set-up and the run with
!>                                         --toggle-collect='start' --toggle-collect='start.*'
!>                                         --toggle-collect='__vci_integrator_MOD_integrate', as
!>                                         profile_peers.sh does)
!>   vci_results_driver long SCENE DIR     long run (>= 10^5 impacts) of the ellipse or the walled
!>                                         pendulum at h = 1e-2: |E - E0| over time
!>
!> Same start as every peer: each variant starts from the exact (q(0), qdot(0)) at t = 0, through
!> init_from_momentum with p(0) = M q̇(0), unless it is a `-pair` variant (the paper's initial
!> pair, kept as a separate labelled row). Step sizes are adjusted so that the final time T is a
!> grid point: h = T/N (momentum start) or T/(N + 1/2) (pair q(0) -+ (h/2) q̇(0) at -+h/2), N the
!> integer nearest to T/h_nominal; every method's final error is then taken at the same T.
!>
!> Timing: each timed repeat creates, initialises and runs an integrator with no observer; wall
!> time by system_clock (median over repeats), CPU time by cpu_time (median). Errors come from
!> one more, untimed, run with a recording observer. Measures: see vci_results_common.
!>
!> Rows: `vci-ld-*` run the scene's own hand-written discrete L_d (vci_model_t); `vci-left-*`,
!> `vci-midpoint-*`, `vci-lobattoS-*` run the scene's continuous model (vci_lagrangian_t) with
!> `integ%set_scheme(...)` (docs/SCHEMES.md). The suffix is the impact condition.
!>
!> EXTENSION POINT: every method row comes from the table built in `variants()` below (label,
!> impact condition, scheme id and stages, the scenes it runs on, its step-size family, its Newton
!> rtol, its long-run step). `make_model` gives each scene's discrete or continuous model, `start`
!> sets the scheme after create. Nothing else changes: the sweep, the CSV columns, the long runs
!> and make_report.py (which reads the method names from the CSV) pick new rows up.
!> The recording observer of the results driver.
module vci_results_recorder
  use vci
  use vci_results_common, only: mass, grav, pend_l, pend_f
  implicit none
  private
  public :: grow, energy_at, constraint_at

  !> Records impacts and the energy error of every state.
  type, public, extends(vci_observer_t) :: recorder_t
    class(vci_model_base_t), pointer :: model => null()
    logical :: reduced_pendulum_energy = .false.  !< pendulum: E from (theta, p_theta), see energy_at
    real(dp) :: e0 = 0.0_dp, emax = 0.0_dp
    real(dp) :: cmax = 0.0_dp   !< pendulum: largest constraint residual at the step ends, see constraint_at
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
    if (self%reduced_pendulum_energy) self%cmax = max(self%cmax, abs(constraint_at(q, p)))
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

  !> The nonholonomic pendulum's constraint phidot = f(theta) thetadot in momentum form over m l^2,
  !> (f sin^2(theta) p_theta - p_phi) / (m l^2) = sin^2(theta) (f thetadot - phidot): finite through
  !> theta = pi, and the same measure as the ODE peers' (results_scene_ode%scene_constraint).
  real(dp) function constraint_at(q, p) result(r)
    real(dp), intent(in) :: q(:), p(:)
    r = (pend_f(q(1)) * sin(q(1))**2 * p(1) - p(2)) / (mass * pend_l**2)
  end function constraint_at

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
  use vci_scene_pendulum_walls_ld, only: pendulum_walls_ld_model
  use vci_scene_fpu_walls, only: fpu_walls_model
  use vci_results_common
  use vci_scene_particle, only: particle_lagrangian_on_floor
  use vci_scene_ellipse, only: ellipse_lagrangian_model
  use vci_scene_pendulum, only: pendulum_lagrangian_model
  use vci_scene_pendulum_walls, only: pendulum_walls_model
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_model, fpu_walls_lagrangian_t
  use vci_results_recorder
  use vci_scene_pendulum_walls_sep, only: pendulum_walls_sep_model
  use results_separable_scenes, only: particle_sep_model, ellipse_sep_model, fpu_sep_model
  implicit none

  !> How the scene's model is discretised. SCHEME_LD (= VCI_SCHEME_DISCRETE): the scene's own
  !> user-written discrete L_d (midpoint rule for the particle, the ellipse, the walled pendulum and
  !> the FPU chain; the paper's left-point L_d for the nonholonomic pendulum). VCI_SCHEME_LEFT,
  !> VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO: the library's schemes on the scene's continuous L.
  integer, parameter :: SCHEME_LD = VCI_SCHEME_DISCRETE

  !> Step-size families (nominal_steps): FINE 1e-1 .. 1e-5, MID 1e-1 .. 1e-4 (the second-order
  !> rows from L, whose small steps the ld rows already cover), COARSE up to 0.5 (high order).
  integer, parameter :: STEPS_FINE = 1, STEPS_MID = 2, STEPS_COARSE = 3

  !> One method row of the report (see EXTENSION POINT in the header).
  type :: variant_t
    character(len=32) :: label = ''
    integer :: impact_mode = VCI_IMPACT_DISCRETE
    logical :: pair_start = .false.     !< the paper's initial pair instead of init_from_momentum
    integer :: scheme = SCHEME_LD
    integer :: stages = 0               !< for Lobatto schemes
    logical :: scenes(N_SCENES) = .true.  !< the scenes it runs on
    integer :: steps = STEPS_FINE
    real(dp) :: rtol = 1.0e-12_dp       !< Newton rtol
    real(dp) :: long_h(2) = 0.0_dp      !< > 0: in the long runs at this step (walled pendulum, ellipse)
    real(dp) :: fpu_h_min = 0.0_dp      !< on the FPU chain, no steps below this (time budget)
  end type variant_t

  logical, parameter :: PAPER(N_SCENES) = [.true., .true., .true., .false., .false.]
  logical, parameter :: NO_FPU(N_SCENES) = [.true., .true., .true., .true., .false.]
  logical, parameter :: HOLONOMIC(N_SCENES) = [.true., .true., .false., .true., .true.]
  logical, parameter :: HOLO_NO_FPU(N_SCENES) = [.true., .true., .false., .true., .false.]
  logical, parameter :: PENDULUM_ONLY(N_SCENES) = [.false., .false., .true., .false., .false.]
  !> the scenes with a separable Lagrangian (constant M): the explicit compositions run there
  logical, parameter :: SEPARABLE(N_SCENES) = [.true., .true., .false., .true., .true.]

  character(len=512) :: mode, target_path, arg3, arg4
  integer :: nargs

  nargs = command_argument_count()
  if (nargs < 2) then
    write (error_unit, '(a)') 'usage: vci_results_driver reference|sweep|richardson PATH | long SCENE DIR | ' // &
      'once SCENE LABEL H'
    stop 2
  end if
  call get_command_argument(1, mode)
  call get_command_argument(2, target_path)
  select case (trim(mode))
  case ('reference')
    ! with a scene argument (the large chain) that scene only
    arg3 = ''
    if (nargs >= 3) call get_command_argument(3, arg3)
    call write_reference(trim(target_path), scene_argument(arg3))
  case ('sweep')
    arg3 = ''; arg4 = ''
    if (nargs >= 3) call get_command_argument(3, arg3)
    if (nargs >= 4) call get_command_argument(4, arg4)
    call sweep(trim(target_path), trim(arg3), scene_argument(arg4))
  case ('richardson'); call richardson(trim(target_path))
  case ('once')
    call get_command_argument(3, arg3)
    call get_command_argument(4, arg4)
    call once(scene_argument(target_path), trim(arg3), trim(arg4))
  case ('long')
    call get_command_argument(3, arg3)
    call long_run(trim(target_path), trim(arg3))
  case default
    write (error_unit, '(a)') 'unknown mode '//trim(mode)
    stop 2
  end select

contains

  !> The method rows. Add new schemes here (EXTENSION POINT).
  !> `left` only with the paper's condition (with `hamiltonian` its first-order momenta make the
  !> wall's energy balance drift, docs/SCHEMES.md). Lobatto s = 1 .. 4 on the nonholonomic pendulum
  !> (constraints at the nodes, issue 25; s = 4 also at Newton rtol 1e-8 and 1e-6, as CVODE's tol is
  !> swept: the `-r8`, `-r6` rows), s = 2 .. 4 on the holonomic scenes; on the FPU chain
  !> midpoint and lobatto s = 2, 4 with the hamiltonian condition (the time budget). The explicit
  !> compositions of order 2 .. 10 (VCI_SCHEME_COMPOSITION, issue 32) on every separable scene; they
  !> always reflect with the Hamiltonian condition (docs/SCHEMES.md), hence the suffix.
  function variants() result(v)
    type(variant_t), allocatable :: v(:)
    integer, parameter :: D = VCI_IMPACT_DISCRETE, H = VCI_IMPACT_HAMILTONIAN
    integer, parameter :: LEFT = VCI_SCHEME_LEFT, MID = VCI_SCHEME_MIDPOINT, LOB = VCI_SCHEME_LOBATTO
    integer, parameter :: COMP = VCI_SCHEME_COMPOSITION
    v = [variant_t('vci-ld-discrete', D, .false., long_h=[1.0e-2_dp, 1.0e-2_dp]), &
         variant_t('vci-ld-hamiltonian', H, .false., long_h=[1.0e-2_dp, 1.0e-2_dp]), &
         variant_t('vci-ld-pair-discrete', D, .true., scenes=PAPER), &
         variant_t('vci-ld-pair-hamiltonian', H, .true., scenes=PAPER), &
         variant_t('vci-left-discrete', D, .false., LEFT, 1, scenes=NO_FPU, steps=STEPS_MID), &
         variant_t('vci-midpoint-discrete', D, .false., MID, 1, scenes=NO_FPU, steps=STEPS_MID), &
         variant_t('vci-midpoint-hamiltonian', H, .false., MID, 1, steps=STEPS_MID), &
         variant_t('vci-lobatto1-discrete', D, .false., LOB, 1, scenes=PENDULUM_ONLY, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp), &
         variant_t('vci-lobatto1-hamiltonian', H, .false., LOB, 1, scenes=PENDULUM_ONLY, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp), &
         variant_t('vci-lobatto2-discrete', D, .false., LOB, 2, scenes=NO_FPU, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp), &
         variant_t('vci-lobatto2-hamiltonian', H, .false., LOB, 2, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp, long_h=[0.0_dp, 1.0e-1_dp]), &
         variant_t('vci-lobatto3-discrete', D, .false., LOB, 3, scenes=NO_FPU, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp), &
         variant_t('vci-lobatto3-hamiltonian', H, .false., LOB, 3, scenes=NO_FPU, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp), &
         variant_t('vci-lobatto4-discrete', D, .false., LOB, 4, scenes=NO_FPU, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp), &
         variant_t('vci-lobatto4-hamiltonian', H, .false., LOB, 4, steps=STEPS_COARSE, &
                   rtol=1.0e-14_dp, long_h=[1.0e-1_dp, 0.0_dp], fpu_h_min=4.9e-2_dp), &
         variant_t('vci-lobatto4-hamiltonian-r8', H, .false., LOB, 4, scenes=PENDULUM_ONLY, steps=STEPS_COARSE, &
                   rtol=1.0e-8_dp), &
         variant_t('vci-lobatto4-hamiltonian-r6', H, .false., LOB, 4, scenes=PENDULUM_ONLY, steps=STEPS_COARSE, &
                   rtol=1.0e-6_dp), &
         variant_t('vci-composition2-hamiltonian', H, .false., COMP, 2, scenes=SEPARABLE, steps=STEPS_MID), &
         variant_t('vci-composition4-hamiltonian', H, .false., COMP, 4, scenes=SEPARABLE, steps=STEPS_COARSE), &
         variant_t('vci-composition6-hamiltonian', H, .false., COMP, 6, scenes=SEPARABLE, steps=STEPS_COARSE), &
         variant_t('vci-composition8-hamiltonian', H, .false., COMP, 8, scenes=SEPARABLE, steps=STEPS_COARSE), &
         variant_t('vci-composition10-hamiltonian', H, .false., COMP, 10, scenes=SEPARABLE, steps=STEPS_COARSE)]
  end function variants

  !> A fresh model of the scene, discretised as the variant says.
  subroutine make_model(scene, var, model)
    integer, intent(in) :: scene
    type(variant_t), intent(in) :: var
    class(vci_model_base_t), allocatable, intent(out) :: model
    if (var%scheme == VCI_SCHEME_COMPOSITION) then
      ! the separable forms (constant M): the explicit compositions need this model kind
      select case (scene)
      case (SCENE_PARTICLE); allocate (model, source=particle_sep_model())
      case (SCENE_ELLIPSE); allocate (model, source=ellipse_sep_model())
      case (SCENE_PWALLS); allocate (model, source=pendulum_walls_sep_model(.true.))
      case (SCENE_FPU); allocate (model, source=fpu_sep_model())
      case default; error stop 'make_model: the nonholonomic pendulum has no separable form'
      end select
    else if (var%scheme == SCHEME_LD) then
      select case (scene)
      case (SCENE_PARTICLE); allocate (model, source=particle_on_floor(mass, grav))
      case (SCENE_ELLIPSE); allocate (model, source=ellipse_model())
      case (SCENE_PENDULUM); allocate (model, source=pendulum_model())
      case (SCENE_PWALLS); allocate (model, source=pendulum_walls_ld_model(pw_wall))
      case default; allocate (model, source=fpu_walls_model(fpu_n, fpu_beta, fpu_w))
      end select
    else
      ! the continuous models (same parameters: the scenes' defaults are the results' set-ups)
      select case (scene)
      case (SCENE_PARTICLE); allocate (model, source=particle_lagrangian_on_floor(mass, grav))
      case (SCENE_ELLIPSE); allocate (model, source=ellipse_lagrangian_model())
      case (SCENE_PENDULUM); allocate (model, source=pendulum_lagrangian_model())
      case (SCENE_PWALLS); allocate (model, source=pendulum_walls_model(.true.))
      case default
        allocate (model, source=fpu_walls_lagrangian_model(fpu_n, fpu_beta, fpu_w))
        ! the large chain declares its tridiagonal Hessians (the banded Newton path, issue 28); the
        ! n = 32 rows stay dense, as measured before
        if (large_chain()) then
          select type (model)
          type is (fpu_walls_lagrangian_t)
            model%band_hessians = .true.
            call model%declare_bandwidth(1)
          end select
        end if
      end select
    end if
  end subroutine make_model

  !> Whether the FPU scene is the large chain of the report (use_large_chain).
  logical function large_chain()
    large_chain = scene_names(SCENE_FPU) == LARGE_CHAIN_NAME
  end function large_chain

  !> Whether a variant runs on the large chain: its dense rows (the hand-written L_d's n x n mixed
  !> Hessian, Lobatto's (s + 1) n stage systems, which do not use the band) would spend the time
  !> budget on dense LU; midpoint from L (banded) and the explicit compositions run (their stage 1
  !> searches the wall estimated first first, 0.2-0.7 ms an impact here since sep32f).
  logical function runs_on_large_chain(var)
    type(variant_t), intent(in) :: var
    runs_on_large_chain = var%impact_mode == VCI_IMPACT_HAMILTONIAN .and. &
      (var%scheme == VCI_SCHEME_MIDPOINT .or. var%scheme == VCI_SCHEME_COMPOSITION)
  end function runs_on_large_chain

  !> The step actually used for a nominal step, so that T = t_final is a grid point.
  real(dp) function grid_step(scene, var, h_nominal, t_end) result(h)
    integer, intent(in) :: scene
    type(variant_t), intent(in) :: var
    real(dp), intent(in) :: h_nominal, t_end
    integer(i8) :: n
    n = max(1_i8, nint(t_end / h_nominal, i8))
    if (var%pair_start .and. scene /= SCENE_PENDULUM) then
      h = t_end / (real(n, dp) + 0.5_dp)          ! the pair at -+h/2: grid (k - 1/2) h
    else
      h = t_end / real(n, dp)
    end if
  end function grid_step

  !> Steps to take after the start so that the last grid time is t_end (h from grid_step).
  integer(i8) function steps_to(scene, var, h, t_end)
    integer, intent(in) :: scene
    type(variant_t), intent(in) :: var
    real(dp), intent(in) :: h, t_end
    if (.not. var%pair_start) then
      steps_to = nint(t_end / h, i8)                 ! t_k = k h from k = 0
    else if (scene == SCENE_PENDULUM) then
      steps_to = nint(t_end / h, i8) - 1_i8          ! pair at 0 and h, t_k = k h from k = 1
    else
      steps_to = nint(t_end / h + 0.5_dp, i8) - 1_i8 ! pair at -+h/2, t_k = (k - 1/2) h from k = 1
    end if
  end function steps_to

  !> Create and initialise an integrator: from the exact (q(0), p(0)), or from the paper's pair.
  subroutine start(scene, var, model, h, integ, stat, max_impacts)
    integer, intent(in) :: scene
    type(variant_t), intent(in) :: var
    class(vci_model_base_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    integer, intent(in), optional :: max_impacts   !< impacts per step (default: the library's, FPU 8)
    real(dp), allocatable :: q0(:), qd0(:), p0(:)
    call initial_state(scene, q0, qd0)
    select type (model)
    class is (vci_model_t)
      call integ%create(model, h, stat)
    class is (vci_lagrangian_t)
      call integ%create(model, h, stat)
      if (stat == VCI_OK) call integ%set_scheme(var%scheme, var%stages, stat)
    class default
      stat = VCI_ERR_ARGUMENT
    end select
    if (stat == VCI_OK) call integ%set_tolerances(0.0_dp, var%rtol, 30, stat)
    if (stat == VCI_OK) call integ%set_impact_energy(var%impact_mode, stat)
    ! n = 32: 8 impacts per step (as measured before); the large chain keeps the library's default,
    ! sized by its 2n walls
    if (stat == VCI_OK .and. scene == SCENE_FPU .and. .not. large_chain()) call integ%set_max_impacts(8, stat)
    if (stat == VCI_OK .and. present(max_impacts)) call integ%set_max_impacts(max_impacts, stat)
    if (stat /= VCI_OK) return
    if (.not. var%pair_start) then
      call initial_momentum(scene, p0)
      call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    else if (scene == SCENE_PENDULUM) then
      call integ%init_from_pair(0.0_dp, q0, q0 + h * qd0, stat)
    else
      call integ%init_from_pair(-0.5_dp * h, q0 - 0.5_dp * h * qd0, q0 + 0.5_dp * h * qd0, stat)
    end if
  end subroutine start

  !> One accuracy run and timed repeats; one CSV row. h is the step from grid_step.
  subroutine measure(unit, scene, var, h)
    integer, intent(in) :: unit, scene
    type(variant_t), intent(in) :: var
    real(dp), intent(in) :: h
    class(vci_model_base_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(recorder_t) :: rec
    real(dp), allocatable :: qref(:), qdref(:), tref(:)
    real(dp) :: walls(MAX_REPEATS), cpus(MAX_REPEATS), w0, c0, e, err_final, err_impact
    integer(i8) :: nsteps
    integer :: stat, rstat, reps, r
    character(len=VCI_MSG_LEN) :: msg
    character(len=16) :: constraint_text

    call make_model(scene, var, model)
    nsteps = steps_to(scene, var, h, t_final(scene))
    ! accuracy run, untimed
    call start(scene, var, model, h, integ, stat)
    rec%model => model
    rec%reduced_pendulum_energy = (scene == SCENE_PENDULUM)
    rec%e0 = exact_energy0(scene)
    allocate (rec%times(64), rec%sample_t(1), rec%sample_e(1))
    if (stat == VCI_OK) then
      e = energy_at(rec, integ%configuration(), integ%momentum())
      rec%emax = abs(e - rec%e0)
      if (scene == SCENE_PENDULUM) rec%cmax = abs(constraint_at(integ%configuration(), integ%momentum()))
      call integ%integrate(nsteps, 1, stat, rec)
    end if
    msg = integ%message()
    if (stat == VCI_OK .and. abs(integ%time() - t_final(scene)) > 1.0e-9_dp * t_final(scene)) then
      write (msg, '(a,es22.15)') 'ended off the final time, at t = ', integ%time()
      stat = -1
    end if
    if (stat /= VCI_OK) then
      write (error_unit, '(a,es9.2,a)') trim(scene_names(scene))//' '//trim(var%label)//' h = ', h, &
        ': '//trim(msg)
      write (unit, '(a,",",a,",",es10.3,",",9(a,","),i0,",nan")') trim(scene_names(scene)), trim(var%label), &
        h, ('nan', r = 1, 9), stat
      return
    end if
    ! every method is compared at the same time T (integ%time() is T up to rounding of k h)
    call reference_at(scene, t_final(scene), qref, qdref, tref, rstat)
    err_final = maxval(abs(integ%configuration() - qref))
    err_impact = impact_time_error(tref, rec%times, rec%n_impacts)
    constraint_text = 'nan'
    if (scene == SCENE_PENDULUM) write (constraint_text, '(es12.5)') rec%cmax

    ! timed repeats: more of them for short runs
    reps = 0
    do r = 1, size(walls)
      w0 = wall_now(); c0 = cpu_now()
      call start(scene, var, model, h, integ, stat)
      call integ%integrate(nsteps, 1, stat)
      walls(r) = wall_now() - w0; cpus(r) = cpu_now() - c0
      reps = r
      if (repeats_done(walls, r)) exit
      if (walls(1) > 2.0_dp) exit
    end do
    write (unit, '(a,",",a,",",es10.3,",",es12.5,",",es12.5,",",i0,",",3(es12.5,","),i0,",",i0,",",i0,",",i0,",",a)') &
      trim(scene_names(scene)), trim(var%label), h, median(walls(1:reps)), median(cpus(1:reps)), reps, &
      err_final, rec%emax, err_impact, rec%n_impacts, size(tref), nsteps, stat, trim(constraint_text)
    flush (unit)
  end subroutine measure

  !> Nominal step sizes of each scene: wide enough that the error spans 1e-2 .. 1e-10 where the
  !> method's order and vci's round-off floor allow, short enough to fit the time budget.
  function nominal_steps(scene, family) result(hs)
    integer, intent(in) :: scene, family
    real(dp), allocatable :: hs(:)
    if (family == STEPS_COARSE) then
      select case (scene)
      case (SCENE_FPU)
        hs = [2.0e-1_dp, 1.0e-1_dp, 5.0e-2_dp, 2.0e-2_dp, 1.0e-2_dp, 5.0e-3_dp, 2.0e-3_dp]
      case default
        ! 4e-2 between 5e-2 and 3e-2: Lobatto-4's error falls ~60x there on the nonholonomic pendulum,
        ! and the 1e-6 level fell between them (issue 25, docs/bench/lobatto.md)
        ! and 5/120 between them: the bench's cheapest step at 1e-6 (docs/bench/lobatto.md)
        hs = [4.0e-1_dp, 3.0e-1_dp, 2.0e-1_dp, 1.5e-1_dp, 1.0e-1_dp, 7.0e-2_dp, 5.0e-2_dp, 5.0_dp / 120.0_dp, &
              4.0e-2_dp, 3.0e-2_dp, 2.0e-2_dp, 1.0e-2_dp, 5.0e-3_dp, 2.0e-3_dp, 1.0e-3_dp]
      end select
      return
    end if
    select case (scene)
    case (SCENE_FPU)
      hs = [5.0e-2_dp, 2.0e-2_dp, 1.0e-2_dp, 5.0e-3_dp, 2.0e-3_dp, 1.0e-3_dp, 5.0e-4_dp, 2.0e-4_dp, 1.0e-4_dp]
    case (SCENE_PWALLS)
      hs = [1.0e-1_dp, 5.0e-2_dp, 2.0e-2_dp, 1.0e-2_dp, 5.0e-3_dp, 2.0e-3_dp, 1.0e-3_dp, 5.0e-4_dp, &
            2.0e-4_dp, 1.0e-4_dp, 5.0e-5_dp, 2.0e-5_dp, 1.0e-5_dp]
    case default
      hs = [1.0e-1_dp, 5.0e-2_dp, 2.0e-2_dp, 1.0e-2_dp, 5.0e-3_dp, 2.0e-3_dp, 1.0e-3_dp, 5.0e-4_dp, &
            2.0e-4_dp, 1.0e-4_dp, 5.0e-5_dp, 2.0e-5_dp, 1.0e-5_dp]
    end select
    if (family == STEPS_MID) hs = pack(hs, hs >= 0.99e-4_dp)
  end function nominal_steps

  !> The step-size sweep of every variant on every scene it runs on; `only` (a label prefix) and
  !> `only_scene` (a scene name), when not empty, restrict it (for trying a new row quickly).
  subroutine sweep(path, only, only_scene)
    character(len=*), intent(in) :: path, only, only_scene
    type(variant_t), allocatable :: vs(:)
    real(dp), allocatable :: hs(:)
    integer :: unit, scene, i, iv
    vs = variants()
    open (newunit=unit, file=path, status='replace', action='write')
    write (unit, '(a)') 'scene,method,param,wall_median,cpu_median,reps,err_final,err_energy,err_impact,' // &
      'n_impacts,n_ref_impacts,steps,status,err_constraint'
    do scene = 1, N_SCENES
      if (len(only_scene) > 0 .and. only_scene /= trim(scene_names(scene))) cycle
      do iv = 1, size(vs)
        if (.not. vs(iv)%scenes(scene)) cycle
        if (scene == SCENE_FPU .and. large_chain() .and. .not. runs_on_large_chain(vs(iv))) cycle
        if (len(only) > 0 .and. index(vs(iv)%label, only) /= 1) cycle
        hs = nominal_steps(scene, vs(iv)%steps)
        if (scene == SCENE_FPU) hs = pack(hs, hs >= vs(iv)%fpu_h_min)
        do i = 1, size(hs)
          call measure(unit, scene, vs(iv), grid_step(scene, vs(iv), hs(i), t_final(scene)))
        end do
      end do
      write (output_unit, '(a)') 'vci sweep: '//trim(scene_names(scene))//' done'
      flush (output_unit)
    end do
    close (unit)
  end subroutine sweep

  !> Exact data at each scene's final time, for the Python peers (JSON).
  subroutine write_reference(path, only_scene)
    character(len=*), intent(in) :: path
    character(len=*), intent(in) :: only_scene   !< a scene name, or empty for every scene
    integer :: unit, scene, rstat, rstat2
    real(dp), allocatable :: q(:), qd(:), times(:), q2(:), qd2(:), times2(:)
    real(dp) :: check
    character(len=*), parameter :: fmt_arr = '(*(es25.17e3,:,","))'
    open (newunit=unit, file=path, status='replace', action='write')
    write (unit, '(a)') '{'
    do scene = 1, N_SCENES
      if (len(only_scene) > 0 .and. only_scene /= trim(scene_names(scene))) cycle
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
      write (unit, '(a)') '],'
      ! the FPU reference checked against itself at half the Taylor step (the others are exact)
      check = 0.0_dp
      if (scene == SCENE_FPU) then
        call fpu_reference(t_final(scene), fpu_ref_steps(2), q2, qd2, times2, rstat2)
        check = max(maxval(abs(q2 - q)), maxval(abs(qd2 - qd)))
        if (size(times2) == size(times)) then
          if (size(times) > 0) check = max(check, maxval(abs(times2 - times)))
        else
          check = huge(1.0_dp)
        end if
        if (rstat2 /= 0) check = huge(1.0_dp)
      end if
      write (unit, '(a,es25.17e3)') '"self_check": ', check
      if (scene < N_SCENES .and. len(only_scene) == 0) then
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
    class(vci_model_base_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(recorder_t) :: rec
    real(dp) :: q(2, size(hs)), ti(3, size(hs)), rq(2), rt(3)
    real(dp), allocatable :: qref(:), qdref(:), tref(:)
    integer :: i, stat, unit, rstat
    type(variant_t), parameter :: pair = variant_t('pair', VCI_IMPACT_DISCRETE, .true.)
    call make_model(SCENE_PENDULUM, pair, model)
    call reference_at(SCENE_PENDULUM, t_final(SCENE_PENDULUM), qref, qdref, tref, rstat)
    do i = 1, size(hs)
      call start(SCENE_PENDULUM, pair, model, hs(i), integ, stat)
      rec = recorder_t()
      rec%model => model
      allocate (rec%times(64), rec%sample_t(1), rec%sample_e(1))
      call integ%integrate(steps_to(SCENE_PENDULUM, pair, hs(i), t_final(SCENE_PENDULUM)), 1, stat, rec)
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

  !> One run of the row `label` on `scene_name` at the nominal step h_text, work in run_once (the
  !> profile of the report's rows: model set-up, create, set_scheme, init and the whole run).
  subroutine once(scene_name, label, h_text)
    character(len=*), intent(in) :: scene_name, label, h_text
    type(variant_t), allocatable :: vs(:)
    real(dp) :: h
    integer :: scene, iv, stat, rstat
    real(dp), allocatable :: q(:), qref(:), qdref(:), tref(:)
    vs = variants()
    scene = findloc(scene_names, scene_name, 1)
    iv = 0
    if (scene > 0) iv = findloc([(vs(iv)%label == label, iv = 1, size(vs))], .true., 1)
    if (scene == 0 .or. iv == 0) then
      write (error_unit, '(a)') 'once: unknown scene or row '//scene_name//' '//label
      stop 2
    end if
    read (h_text, *) h
    h = grid_step(scene, vs(iv), h, t_final(scene))
    call run_once(scene, vs(iv), h, q, stat)
    call reference_at(scene, t_final(scene), qref, qdref, tref, rstat)
    write (output_unit, '(a,es10.3,a,i0,a,es10.3)') trim(label)//' h = ', h, ' status ', stat, ' final error ', &
      maxval(abs(q - qref))
  end subroutine once

  subroutine run_once(scene, var, h, q, stat)
    integer, intent(in) :: scene
    type(variant_t), intent(in) :: var
    real(dp), intent(in) :: h
    real(dp), allocatable, intent(out) :: q(:)
    integer, intent(out) :: stat
    class(vci_model_base_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    call make_model(scene, var, model)
    call start(scene, var, model, h, integ, stat)
    if (stat == VCI_OK) call integ%integrate(steps_to(scene, var, h, t_final(scene)), 1, stat)
    q = integ%configuration()
  end subroutine run_once

  !> Long run of the ellipse (1.1e5 s) or the walled pendulum (6e4 s), >= 10^5 impacts, of every
  !> variant with long_h > 0 (the ld rows at h = 1e-2 with both impact conditions; the best
  !> Lobatto row of each scene's sweep with the hamiltonian condition at h = 0.1, a cost near
  !> CVODE's: s = 4 on the walled pendulum, s = 2 on the ellipse), from the exact start: |E - E0| over time
  !> (largest of each window of 10 s), and the run's CPU time with the recording observer (the
  !> peers' long runs also evaluate the energy at every step).
  subroutine long_run(scene_name, dir)
    character(len=*), intent(in) :: scene_name, dir
    type(variant_t), allocatable :: vs(:)
    real(dp), parameter :: window = 10.0_dp
    real(dp) :: h
    class(vci_model_base_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(recorder_t) :: rec
    real(dp) :: w0, c0, wall, cpu, t_end
    integer(i8) :: nsteps
    integer :: iv, stat, unit, sunit, i, scene
    character(len=64) :: name
    select case (scene_name)
    case ('ellipse'); scene = SCENE_ELLIPSE; t_end = 1.1e5_dp
    case ('pendulum_walls'); scene = SCENE_PWALLS; t_end = 6.0e4_dp
    case default
      write (error_unit, '(a)') 'long: scene must be ellipse or pendulum_walls'
      stop 2
    end select
    vs = variants()
    open (newunit=sunit, file=dir//'/long_'//scene_name//'_vci.csv', status='replace', action='write')
    write (sunit, '(a)') 'scene,method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status'
    do iv = 1, size(vs)
      h = vs(iv)%long_h(merge(1, 2, scene == SCENE_PWALLS))
      if (vs(iv)%pair_start .or. h <= 0.0_dp .or. .not. vs(iv)%scenes(scene)) cycle
      nsteps = nint(t_end / h, i8)
      call make_model(scene, vs(iv), model)
      rec = recorder_t()
      rec%model => model
      rec%block = nint(window / h, i8)
      rec%e0 = exact_energy0(scene)
      allocate (rec%times(1024), rec%sample_t(1024), rec%sample_e(1024))
      w0 = wall_now(); c0 = cpu_now()
      ! up to 64 impacts per step: the ellipse's long chaotic run has bursts of chatter that a long
      ! step (lobatto) would otherwise refuse as more than the default 16
      call start(scene, vs(iv), model, h, integ, stat, max_impacts=64)
      if (stat == VCI_OK) call integ%integrate(nsteps, 1, stat, rec)
      wall = wall_now() - w0; cpu = cpu_now() - c0
      if (stat /= VCI_OK) write (error_unit, '(a)') 'long run: '//integ%message()
      name = vs(iv)%label
      write (sunit, '(a,",",a,",",es10.3,",",es12.5,",",es12.5,",",es12.5,",",es12.5,",",i0,",",es14.7,",",i0)') &
        scene_name, trim(name), h, wall, cpu, rec%emax, rec%sample_e(max(1, rec%n_samples)), &
        rec%n_impacts, integ%time(), stat
      open (newunit=unit, file=dir//'/long_'//scene_name//'_'//trim(name)//'.csv', status='replace', action='write')
      write (unit, '(a)') 't,energy_error'
      do i = 1, rec%n_samples
        write (unit, '(es14.7,",",es12.5)') rec%sample_t(i), rec%sample_e(i)
      end do
      close (unit)
      write (output_unit, '(a,f8.1,a,i0,a)') 'vci long run: '//scene_name//' '//trim(name)//' done (', cpu, &
        ' s CPU, ', rec%n_impacts, ' impacts)'
      flush (output_unit)
    end do
    close (sunit)
  end subroutine long_run
end program vci_results_driver
