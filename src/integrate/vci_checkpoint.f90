!> The checkpoint: everything the driver needs to continue a run bit for bit (docs/DESIGN.md §5),
!> as a type of its own with named fields and a version, so that any output can store it and read it
!> back without knowing the driver. The driver produces it (`integ%checkpoint()`) and consumes it
!> (`integ%restore(cp, stat)`); an output that can restart stores `to_record()` and rebuilds it with
!> `from_record`, the only place that knows the order of the fields in the flat record.
module vci_checkpoint
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use vci_kinds, only: dp, i8
  use vci_status, only: VCI_OK, VCI_ERR_ARGUMENT, VCI_ERR_MEMORY
  implicit none
  private

  !> Layout version of the checkpoint (bumped whenever a field is added, removed or reordered).
  integer, parameter, public :: VCI_CHECKPOINT_VERSION = 4
  !> The oldest layout version from_record still reads (its missing fields start empty: see from_record).
  integer, parameter, public :: VCI_CHECKPOINT_OLDEST = 3

  !> Scalars at the head of the record: step, t0, h, step_energy, arriving_energy, arriving_direction.
  integer, parameter :: head = 6

  !> The state a run continues from bit for bit: the driver's `checkpoint()` gives it, outputs store
  !> it (`to_record`), `restore` starts from it.
  type, public :: vci_checkpoint_t
    integer :: version = VCI_CHECKPOINT_VERSION  !< layout version (VCI_CHECKPOINT_VERSION when made here)
    real(dp) :: t0 = 0.0_dp                 !< time of index 0: t = t0 + step * h without drift
    real(dp) :: h = 0.0_dp                  !< step length the run used (a restore must match it)
    integer(i8) :: step = 0_i8              !< index of the state
    real(dp), allocatable :: q(:)           !< configuration
    real(dp), allocatable :: p(:)           !< momentum
    real(dp), allocatable :: lambda(:)      !< multipliers of the last step (size m)
    real(dp), allocatable :: velocity(:)    !< forward-time velocity of the last sub-step: Newton's first guess
    real(dp) :: step_energy = 0.0_dp        !< E_d of the last step (NaN before the first)
    real(dp) :: arriving_energy = 0.0_dp    !< E_d of the sub-step that arrived at q (a start on a wall needs it)
    integer :: arriving_direction = 0       !< direction in which arriving_energy is known (0: unknown)
    ! The predictor's history (version 2): velocity and multipliers of the steps before the last,
    ! from |predictor_depth| consecutive regular steps in direction sign(predictor_depth)
    real(dp), allocatable :: velocity_before(:)  !< (predictor) velocity of the step before the last
    real(dp), allocatable :: lambda_before(:)    !< (predictor) multipliers of the step before the last
    real(dp), allocatable :: lambda_before2(:)   !< (predictor) multipliers of the step before that
    integer :: predictor_depth = 0               !< (predictor) signed count of consecutive regular steps
    !> (version 3) what compensated summation carries beyond q's rounding (continuous models'
    !> left/midpoint; zero otherwise)
    real(dp), allocatable :: position_lo(:)
    !> Newton's factors kept for simplified Newton (systems of 16+ unknowns reuse them across
    !> solves): factors_n unknowns (0: none), the key of the family of systems they serve, row
    !> weights, LU and pivots. Not in the flat record (their size is not n's): factors_record.
    integer :: factors_n = 0
    real(dp) :: factors_key = 0.0_dp                 !< the family of systems the factors serve
    real(dp), allocatable :: factors_rw(:)           !< row weights of the factored matrix
    real(dp), allocatable :: factors_lu(:, :)        !< the LU factors (factors_n x factors_n)
    integer, allocatable :: factors_pivots(:)        !< LAPACK's pivot indices
    !> (version 4) the run's safety-net counts up to this state: steps taken as equal sub-steps and
    !> the most sub-steps one of them needed (vci_stats_t's split_steps, largest_split, over the run
    !> and its restarts rather than the integrator's life)
    integer(i8) :: split_steps = 0_i8
    integer(i8) :: largest_split = 0_i8   !< (version 4) see split_steps
    !> (version 4) the scheme's Newton start memory (Lobatto with constraints: the last regular
    !> step's stage and multiplier polynomials), opaque here; empty: none (the scheme starts as after
    !> an initialisation). Not in the flat record (its size is the scheme's): start_record.
    real(dp), allocatable :: start(:)
  contains
    !> the checkpoint as one float64 vector (what outputs store)
    procedure :: to_record
    !> to_record with a status (VCI_ERR_MEMORY) and an optional value before it (outputs use this)
    procedure :: record_into
    !> rebuild from such a vector of a given layout version
    procedure :: from_record
    !> Newton's kept factors as one float64 vector (stored beside the record)
    procedure :: factors_record
    !> factors_record with a status (VCI_ERR_MEMORY)
    procedure :: factors_record_into
    !> take the factors from such a vector, if it belongs to this checkpoint's step
    procedure :: from_factors_record
    !> the scheme's start memory as one float64 vector (stored beside the record)
    procedure :: start_record
    !> start_record with a status (VCI_ERR_MEMORY)
    procedure :: start_record_into
    !> take the start memory from such a vector, if it belongs to this checkpoint's step
    procedure :: from_start_record
    !> the time of the checkpoint's state, t0 + step h
    procedure :: time => checkpoint_time
    !> a copy of another checkpoint, or VCI_ERR_MEMORY and an empty checkpoint (never the runtime's stop)
    procedure :: copy_from
    !> no arrays: an empty checkpoint (what restore refuses)
    procedure :: release
  end type vci_checkpoint_t

  public :: vci_checkpoint_record_size, vci_checkpoint_from_state, copy_vector

contains

  !> Length of the flat record of a model with n coordinates and m constraints, in layout `version`
  !> (default: this library's).
  pure integer function vci_checkpoint_record_size(n, m, version)
    integer, intent(in) :: n, m
    integer, intent(in), optional :: version
    vci_checkpoint_record_size = head + 5 * n + 3 * m + 1
    if (present(version)) then
      if (version < 4) return
    end if
    vci_checkpoint_record_size = vci_checkpoint_record_size + 2   ! (version 4) split_steps, largest_split
  end function vci_checkpoint_record_size

  !> The time of the checkpoint's state.
  pure real(dp) function checkpoint_time(self)
    class(vci_checkpoint_t), intent(in) :: self
    checkpoint_time = self%t0 + real(self%step, dp) * self%h
  end function checkpoint_time

  !> A copy of src, every array allocated with stat=: intrinsic assignment allocates without one and
  !> ends the program when memory runs out (issue 24). On failure self is empty (release) and stat
  !> = VCI_ERR_MEMORY.
  subroutine copy_from(self, src, stat)
    class(vci_checkpoint_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: src
    integer, intent(out) :: stat
    call self%release()
    stat = 0
    call copy_vector(src%q, self%q, stat); call copy_vector(src%p, self%p, stat)
    call copy_vector(src%lambda, self%lambda, stat); call copy_vector(src%velocity, self%velocity, stat)
    call copy_vector(src%velocity_before, self%velocity_before, stat)
    call copy_vector(src%lambda_before, self%lambda_before, stat)
    call copy_vector(src%lambda_before2, self%lambda_before2, stat)
    call copy_vector(src%position_lo, self%position_lo, stat)
    call copy_vector(src%factors_rw, self%factors_rw, stat); call copy_vector(src%start, self%start, stat)
    if (stat == 0 .and. allocated(src%factors_lu)) allocate (self%factors_lu, source=src%factors_lu, stat=stat)
    if (stat == 0 .and. allocated(src%factors_pivots)) &
      allocate (self%factors_pivots, source=src%factors_pivots, stat=stat)
    if (stat /= 0) then
      call self%release(); stat = VCI_ERR_MEMORY; return
    end if
    self%version = src%version; self%t0 = src%t0; self%h = src%h; self%step = src%step
    self%step_energy = src%step_energy; self%arriving_energy = src%arriving_energy
    self%arriving_direction = src%arriving_direction; self%predictor_depth = src%predictor_depth
    self%factors_n = src%factors_n; self%factors_key = src%factors_key
    self%split_steps = src%split_steps; self%largest_split = src%largest_split
    stat = VCI_OK
  end subroutine copy_from

  !> to = from (when from is allocated and no earlier copy failed: stat = 0 on entry).
  subroutine copy_vector(from, to, stat)
    real(dp), allocatable, intent(in) :: from(:)
    real(dp), allocatable, intent(inout) :: to(:)
    integer, intent(inout) :: stat
    if (stat == 0 .and. allocated(from)) allocate (to, source=from, stat=stat)
  end subroutine copy_vector

  !> Every array deallocated and the factors gone: an empty checkpoint, which restore refuses.
  subroutine release(self)
    class(vci_checkpoint_t), intent(inout) :: self
    if (allocated(self%q)) deallocate (self%q)
    if (allocated(self%p)) deallocate (self%p)
    if (allocated(self%lambda)) deallocate (self%lambda)
    if (allocated(self%velocity)) deallocate (self%velocity)
    if (allocated(self%velocity_before)) deallocate (self%velocity_before)
    if (allocated(self%lambda_before)) deallocate (self%lambda_before)
    if (allocated(self%lambda_before2)) deallocate (self%lambda_before2)
    if (allocated(self%position_lo)) deallocate (self%position_lo)
    if (allocated(self%factors_rw)) deallocate (self%factors_rw)
    if (allocated(self%factors_lu)) deallocate (self%factors_lu)
    if (allocated(self%factors_pivots)) deallocate (self%factors_pivots)
    if (allocated(self%start)) deallocate (self%start)
    self%factors_n = 0
  end subroutine release

  !> The checkpoint as one float64 vector [step, t0, h, step_energy, arriving_energy,
  !> arriving_direction, q(n), p(n), velocity(n), lambda(m), then (version 2) velocity_before(n),
  !> lambda_before(m), lambda_before2(m), predictor_depth, then (version 3) position_lo(n), then
  !> (version 4) split_steps, largest_split] (integers are exact in float64: counts below 2^53), so
  !> that an output writes it in one piece. The version is stored beside it by the output.
  pure function to_record(self) result(rec)
    class(vci_checkpoint_t), intent(in) :: self
    real(dp), allocatable :: rec(:)
    integer :: st
    call self%record_into(rec, st)   ! (rec unallocated when memory ran out: record_into says so)
  end function to_record

  !> to_record's vector, allocated with stat= (the record is n-sized, its copy not tiny: issue 24),
  !> after `lead` when given (an output's row number). stat = VCI_ERR_MEMORY, rec unallocated, when
  !> it cannot be allocated.
  pure subroutine record_into(self, rec, stat, lead)
    class(vci_checkpoint_t), intent(in) :: self
    real(dp), allocatable, intent(out) :: rec(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: lead
    integer :: o
    o = 0
    if (present(lead)) o = 1
    allocate (rec(o + head + size(self%q) + size(self%p) + size(self%velocity) + size(self%lambda) + &
                  size(self%velocity_before) + size(self%lambda_before) + size(self%lambda_before2) + 1 + &
                  size(self%position_lo) + 2), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    if (present(lead)) rec(1) = lead
    call put(rec, o, [real(self%step, dp), self%t0, self%h, self%step_energy, self%arriving_energy, &
                      real(self%arriving_direction, dp)])
    call put(rec, o, self%q); call put(rec, o, self%p); call put(rec, o, self%velocity); call put(rec, o, self%lambda)
    call put(rec, o, self%velocity_before); call put(rec, o, self%lambda_before); call put(rec, o, self%lambda_before2)
    call put(rec, o, [real(self%predictor_depth, dp)]); call put(rec, o, self%position_lo)
    call put(rec, o, [real(self%split_steps, dp), real(self%largest_split, dp)])
    stat = VCI_OK
  end subroutine record_into

  !> rec(o+1:o+size(v)) = v, o past it.
  pure subroutine put(rec, o, v)
    real(dp), intent(inout) :: rec(:)
    integer, intent(inout) :: o
    real(dp), intent(in) :: v(:)
    rec(o + 1:o + size(v)) = v
    o = o + size(v)
  end subroutine put

  !> Rebuild from a record of `version` written by to_record for sizes n, m. Versions from
  !> VCI_CHECKPOINT_OLDEST on are read; a version-3 record has no split counts (0) and comes without
  !> the scheme's start memory, so a constrained Lobatto run continues from it to solver tolerance,
  !> not bit for bit (docs/DESIGN.md, "Restart bit for bit"). A newer version is refused
  !> (VCI_ERR_ARGUMENT); VCI_ERR_MEMORY, self empty, when its arrays cannot be allocated.
  subroutine from_record(self, rec, n, m, version, stat)
    class(vci_checkpoint_t), intent(inout) :: self
    real(dp), intent(in) :: rec(:)
    integer, intent(in) :: n, m, version
    integer, intent(out) :: stat
    integer :: o, st
    stat = VCI_ERR_ARGUMENT
    if (version < VCI_CHECKPOINT_OLDEST .or. version > VCI_CHECKPOINT_VERSION) return
    if (size(rec) /= vci_checkpoint_record_size(n, m, version)) return
    o = head + 5 * n + 3 * m + 1
    self%split_steps = 0_i8; self%largest_split = 0_i8
    if (version >= 4) then
      if (.not. (rec(o + 1) >= 0.0_dp .and. rec(o + 1) <= 2.0_dp**53 .and. rec(o + 2) >= 0.0_dp .and. &
                 rec(o + 2) <= 2.0_dp**31)) return
      self%split_steps = nint(rec(o + 1), i8); self%largest_split = nint(rec(o + 2), i8)
    end if
    ! allocated here with stat= (the assignments below would reallocate without one)
    call self%release()
    allocate (self%q(n), self%p(n), self%velocity(n), self%lambda(m), self%velocity_before(n), &
              self%lambda_before(m), self%lambda_before2(m), self%position_lo(n), stat=st)
    if (st /= 0) then
      call self%release(); stat = VCI_ERR_MEMORY; return
    end if
    self%version = version
    self%step = nint(rec(1), i8); self%t0 = rec(2); self%h = rec(3)
    self%step_energy = rec(4); self%arriving_energy = rec(5); self%arriving_direction = nint(rec(6))
    self%q = rec(head + 1:head + n)
    self%p = rec(head + n + 1:head + 2 * n)
    self%velocity = rec(head + 2 * n + 1:head + 3 * n)
    self%lambda = rec(head + 3 * n + 1:head + 3 * n + m)
    self%velocity_before = rec(head + 3 * n + m + 1:head + 4 * n + m)
    self%lambda_before = rec(head + 4 * n + m + 1:head + 4 * n + 2 * m)
    self%lambda_before2 = rec(head + 4 * n + 2 * m + 1:head + 4 * n + 3 * m)
    self%predictor_depth = nint(rec(head + 4 * n + 3 * m + 1))
    self%position_lo = rec(head + 4 * n + 3 * m + 2:head + 5 * n + 3 * m + 1)
    stat = VCI_OK
  end subroutine from_record

  !> Newton's kept factors as one float64 vector [step, factors_n, factors_key, rw(nf), pivots(nf),
  !> lu(nf*nf)] (the step ties it to its checkpoint; integers are exact in float64).
  pure function factors_record(self) result(rec)
    class(vci_checkpoint_t), intent(in) :: self
    real(dp), allocatable :: rec(:)
    integer :: st
    call self%factors_record_into(rec, st)
  end function factors_record

  !> factors_record's vector, allocated with stat= (nf^2 values): stat = VCI_ERR_MEMORY, rec
  !> unallocated, when it cannot be.
  pure subroutine factors_record_into(self, rec, stat)
    class(vci_checkpoint_t), intent(in) :: self
    real(dp), allocatable, intent(out) :: rec(:)
    integer, intent(out) :: stat
    integer :: o, nf, j
    nf = max(0, self%factors_n)
    allocate (rec(3 + 2 * nf + nf * nf), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    rec(1:3) = [real(self%step, dp), real(nf, dp), self%factors_key]
    if (nf == 0) rec(3) = 0.0_dp
    o = 3
    if (nf > 0) then
      ! element and column wise: no temporary of nf or nf^2 values (they allocate without stat=)
      call put(rec, o, self%factors_rw)
      do j = 1, nf
        rec(o + j) = real(self%factors_pivots(j), dp)
      end do
      o = o + nf
      do j = 1, nf
        call put(rec, o, self%factors_lu(:, j))
      end do
    end if
    stat = VCI_OK
  end subroutine factors_record_into

  !> Take the factors from a record of factors_record, if it belongs to this checkpoint's step and
  !> is well formed; else none (a restart is then correct, not bitwise). stat: VCI_ERR_ARGUMENT when
  !> the record was refused.
  subroutine from_factors_record(self, rec, stat)
    class(vci_checkpoint_t), intent(inout) :: self
    real(dp), intent(in) :: rec(:)
    integer, intent(out) :: stat
    integer :: nf, st
    self%factors_n = 0; self%factors_key = 0.0_dp
    stat = VCI_ERR_ARGUMENT
    if (size(rec) < 3) return
    if (rec(1) /= real(self%step, dp) .or. .not. (rec(2) >= 0.0_dp .and. rec(2) <= 46340.0_dp)) return
    if (rec(2) /= aint(rec(2))) return
    nf = int(rec(2))
    if (size(rec, kind=i8) /= 3_i8 + 2_i8 * nf + int(nf, i8)**2) return
    if (nf == 0) then
      stat = VCI_OK; return
    end if
    if (any(rec(4 + nf:3 + 2 * nf) /= aint(rec(4 + nf:3 + 2 * nf)))) return
    if (any(rec(4 + nf:3 + 2 * nf) < 1.0_dp) .or. any(rec(4 + nf:3 + 2 * nf) > real(nf, dp))) return
    allocate (self%factors_rw(nf), self%factors_pivots(nf), self%factors_lu(nf, nf), stat=st)
    if (st /= 0) return
    self%factors_key = rec(3)
    self%factors_rw = rec(4:3 + nf)
    self%factors_pivots = nint(rec(4 + nf:3 + 2 * nf))
    self%factors_lu = reshape(rec(4 + 2 * nf:), [nf, nf])
    self%factors_n = nf
    stat = VCI_OK
  end subroutine from_factors_record

  !> The scheme's start memory as one float64 vector [step, length, start(length)] (the step ties it
  !> to its checkpoint; length 0: none).
  pure function start_record(self) result(rec)
    class(vci_checkpoint_t), intent(in) :: self
    real(dp), allocatable :: rec(:)
    integer :: st
    call self%start_record_into(rec, st)
  end function start_record

  !> start_record's vector, allocated with stat=: stat = VCI_ERR_MEMORY, rec unallocated, when it
  !> cannot be.
  pure subroutine start_record_into(self, rec, stat)
    class(vci_checkpoint_t), intent(in) :: self
    real(dp), allocatable, intent(out) :: rec(:)
    integer, intent(out) :: stat
    integer :: length
    length = 0
    if (allocated(self%start)) length = size(self%start)
    allocate (rec(2 + length), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    rec(1:2) = [real(self%step, dp), real(length, dp)]
    if (length > 0) rec(3:) = self%start
    stat = VCI_OK
  end subroutine start_record_into

  !> Take the start memory from a record of start_record, if it belongs to this checkpoint's step and
  !> is well formed (the scheme checks its size and values when restored); else none (the restart
  !> is then correct, not bitwise). stat: VCI_ERR_ARGUMENT when the record was refused.
  subroutine from_start_record(self, rec, stat)
    class(vci_checkpoint_t), intent(inout) :: self
    real(dp), intent(in) :: rec(:)
    integer, intent(out) :: stat
    integer :: st
    if (allocated(self%start)) deallocate (self%start)
    stat = VCI_ERR_ARGUMENT
    if (size(rec) < 2) return
    if (rec(1) /= real(self%step, dp) .or. rec(2) /= real(size(rec) - 2, dp)) return
    stat = VCI_OK
    if (size(rec) == 2) return
    allocate (self%start(size(rec) - 2), stat=st)
    if (st /= 0) then
      stat = VCI_ERR_ARGUMENT; return
    end if
    self%start = rec(3:)
  end subroutine from_start_record

  !> A checkpoint that knows only a state (t, q, p, lambda) and the step length, as read from an
  !> output that stores no checkpoint: index 0 at t, no solver memory (like init_from_momentum).
  !> stat (optional): VCI_ERR_MEMORY, and an empty checkpoint, when its arrays cannot be allocated.
  function vci_checkpoint_from_state(t, h, q, p, lambda, stat) result(cp)
    real(dp), intent(in) :: t, h, q(:), p(:), lambda(:)
    integer, intent(out), optional :: stat
    type(vci_checkpoint_t) :: cp
    integer :: st
    if (present(stat)) stat = VCI_ERR_MEMORY
    cp%t0 = t; cp%h = h; cp%step = 0_i8
    ! allocated before the copies: assigning to the unallocated components of a function result made
    ! gfortran 12 -O2 warn that their descriptors are read uninitialised (-Wuninitialized)
    allocate (cp%q(size(q)), cp%p(size(p)), cp%lambda(size(lambda)), cp%velocity(size(q)), &
              cp%velocity_before(size(q)), cp%lambda_before(size(lambda)), cp%lambda_before2(size(lambda)), &
              cp%position_lo(size(q)), stat=st)
    if (st /= 0) then
      call cp%release(); return
    end if
    cp%q = q; cp%p = p; cp%lambda = lambda
    cp%velocity = 0.0_dp; cp%velocity_before = 0.0_dp; cp%lambda_before = 0.0_dp; cp%lambda_before2 = 0.0_dp
    cp%predictor_depth = 0
    cp%position_lo = 0.0_dp
    if (present(stat)) stat = VCI_OK
    cp%arriving_direction = 0
    cp%arriving_energy = ieee_value(1.0_dp, ieee_quiet_nan)
    cp%step_energy = ieee_value(1.0_dp, ieee_quiet_nan)
  end function vci_checkpoint_from_state
end module vci_checkpoint
