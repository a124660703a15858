!> What the ensemble tests share: a factory whose members are the paper's ellipse or a member made
!> to fail on purpose, tables of perturbed ellipse starts, and a bitwise comparison of results.
module vci_ens_test_support
  use vci
  use vci_ensemble
  use vci_scene_ellipse, only: ellipse_t, ellipse_model
  use vci_scene_particle, only: particle_t, particle_on_floor
  use vci_test_scenes, only: ellipse_q0, ellipse_qdot0
  implicit none
  private

  !> Member kinds (params(1) of the test table).
  integer, parameter, public :: KIND_ELLIPSE = 0, KIND_CALLBACK_FAILS = 1, KIND_FACTORY_FAILS = 2, &
                                KIND_WRONG_N = 3

  !> The ellipse with mutable state: counts its D1 calls and fails once it has made `fail_after`
  !> of them (0: never). Members sharing one such model would change each other's results.
  type, extends(ellipse_t), public :: counting_ellipse_t
    integer :: calls = 0, fail_after = 0
  contains
    procedure :: d1 => counting_d1
  end type counting_ellipse_t

  !> params(1): a KIND_*; params(2): the D1 call after which a KIND_CALLBACK_FAILS member fails.
  type, extends(vci_model_factory_t), public :: test_factory_t
  contains
    procedure :: build => test_build
  end type test_factory_t

  public :: ellipse_table, perturbed_pair, results_identical, bits_equal, newton_iterations_of

  !> The fixed direction of the perturbations in (q(0), qdot(0)) (normalised in perturbed_pair).
  real(dp), parameter :: direction6(6) = [1.0_dp, 2.0_dp, 3.0_dp, -1.0_dp, -2.0_dp, 1.0_dp]

contains

  subroutine counting_d1(self, q, v, h, out, stat)
    class(counting_ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    self%calls = self%calls + 1
    if (self%fail_after > 0 .and. self%calls > self%fail_after) then
      out = 0.0_dp
      stat = 1
      return
    end if
    call self%ellipse_t%d1(q, v, h, out, stat)
  end subroutine counting_d1

  subroutine test_build(self, member, params, model, stat)
    class(test_factory_t), intent(in) :: self
    integer, intent(in) :: member
    real(dp), intent(in) :: params(:)
    class(vci_model_t), allocatable, intent(out) :: model
    integer, intent(inout) :: stat
    type(counting_ellipse_t) :: e
    integer :: kind
    kind = KIND_ELLIPSE
    if (size(params) >= 1) kind = nint(params(1))
    select case (kind)
    case (KIND_FACTORY_FAILS)
      stat = 7
    case (KIND_WRONG_N)
      allocate (model, source=particle_on_floor(1.0_dp, 9.8_dp))
    case default
      e%ellipse_t = ellipse_model()
      if (kind == KIND_CALLBACK_FAILS) e%fail_after = nint(params(2))
      allocate (model, source=e)
    end select
  end subroutine test_build

  !> Newton iterations an integrator made: the one place the tests read an integrator's component
  !> (the library's own reads are in vci_ensemble's integrator_extras); becomes an accessor call.
  integer(i8) function newton_iterations_of(integ)
    type(vci_integrator_t), intent(in) :: integ
    type(vci_stats_t) :: stats
    stats = integ%statistics()
    newton_iterations_of = stats%newton_iterations
  end function newton_iterations_of

  !> The examples' midpoint pair around the paper's start perturbed by delta along direction6.
  subroutine perturbed_pair(delta, h, t0, q0, q1)
    real(dp), intent(in) :: delta, h
    real(dp), intent(out) :: t0, q0(3), q1(3)
    real(dp) :: x(3), xd(3), u(6)
    u = direction6 / norm2(direction6)
    x = ellipse_q0 + delta * u(1:3)
    xd = ellipse_qdot0 + delta * u(4:6)
    t0 = -0.5_dp * h
    q0 = x - 0.5_dp * h * xd
    q1 = x + 0.5_dp * h * xd
  end subroutine perturbed_pair

  !> A table of ellipse members: member i perturbed by deltas(i), of kind kinds(i) (params(2) = fail_after).
  function ellipse_table(deltas, kinds, h, fail_after) result(table)
    real(dp), intent(in) :: deltas(:)
    integer, intent(in) :: kinds(:)
    real(dp), intent(in) :: h
    integer, intent(in) :: fail_after
    type(vci_ensemble_table_t) :: table
    integer :: i, nm
    nm = size(deltas)
    allocate (table%t0(nm), table%q0(3, nm), table%v0(3, nm), table%params(2, nm))
    do i = 1, nm
      call perturbed_pair(deltas(i), h, table%t0(i), table%q0(:, i), table%v0(:, i))
      table%params(:, i) = [real(kinds(i), dp), real(fail_after, dp)]
    end do
  end function ellipse_table

  !> Bitwise equality of two real arrays of any shape (NaN equals the same NaN).
  logical function bits_equal(a, b)
    real(dp), intent(in) :: a(..), b(..)
    bits_equal = .false.
    if (size(a) /= size(b)) return
    select rank (a)
    rank (1)
      select rank (b)
      rank (1)
        bits_equal = all(transfer(a, [0_i8]) == transfer(b, [0_i8]))
      end select
    rank (2)
      select rank (b)
      rank (2)
        bits_equal = all(transfer(a, [0_i8]) == transfer(b, [0_i8]))
      end select
    rank (3)
      select rank (b)
      rank (3)
        bits_equal = all(transfer(a, [0_i8]) == transfer(b, [0_i8]))
      end select
    end select
  end function bits_equal

  !> Members ja .. ja + count - 1 of `a` against jb .. of `b`: bitwise equal in everything that is
  !> reproducible (all but the thread and the wall time). `why` names the first difference.
  logical function results_identical(a, b, why, ja, jb, count) result(same)
    type(vci_ensemble_results_t), intent(in) :: a, b
    character(len=:), allocatable, intent(out) :: why
    integer, intent(in), optional :: ja, jb, count
    integer :: i0, k0, c, i1, k1
    i0 = 1; k0 = 1; c = a%count
    if (present(ja)) i0 = ja
    if (present(jb)) k0 = jb
    if (present(count)) c = count
    i1 = i0 + c - 1; k1 = k0 + c - 1
    same = .false.
    why = 'shapes'
    if (a%n /= b%n .or. a%impact_cap /= b%impact_cap .or. a%samples /= b%samples) return
    why = 'status'
    if (any(a%status(i0:i1) /= b%status(k0:k1))) return
    why = 'message'      ! the file keeps 256 characters of a message (VCI_ENSEMBLE_MESSAGE_LEN)
    if (any(a%message(i0:i1)(1:256) /= b%message(k0:k1)(1:256))) return
    why = 't'
    if (.not. bits_equal(a%t(i0:i1), b%t(k0:k1))) return
    why = 'q'
    if (.not. bits_equal(a%q(:, i0:i1), b%q(:, k0:k1))) return
    why = 'p'
    if (.not. bits_equal(a%p(:, i0:i1), b%p(:, k0:k1))) return
    why = 'steps/impacts/newton_iterations'
    if (any(a%steps(i0:i1) /= b%steps(k0:k1)) .or. any(a%impacts(i0:i1) /= b%impacts(k0:k1)) .or. &
        any(a%newton_iterations(i0:i1) /= b%newton_iterations(k0:k1))) return
    why = 'impact_t'
    if (.not. bits_equal(a%impact_t(:, i0:i1), b%impact_t(:, k0:k1))) return
    why = 'impact_gap'
    if (any(a%impact_gap(:, i0:i1) /= b%impact_gap(:, k0:k1))) return
    why = 'energy'
    if (any(a%energy_kind(i0:i1) /= b%energy_kind(k0:k1))) return
    if (.not. (bits_equal(a%energy_start(i0:i1), b%energy_start(k0:k1)) .and. &
               bits_equal(a%energy_end(i0:i1), b%energy_end(k0:k1)) .and. &
               bits_equal(a%energy_change(i0:i1), b%energy_change(k0:k1)))) return
    why = 'trajectory'
    if (any(a%traj_count(i0:i1) /= b%traj_count(k0:k1))) return
    if (.not. (bits_equal(a%traj_t(:, i0:i1), b%traj_t(:, k0:k1)) .and. &
               bits_equal(a%traj_q(:, :, i0:i1), b%traj_q(:, :, k0:k1)) .and. &
               bits_equal(a%traj_p(:, :, i0:i1), b%traj_p(:, :, k0:k1)))) return
    why = ''
    same = .true.
  end function results_identical
end module vci_ens_test_support
