!> A compiled DOP853 for the report's peers: Dormand & Prince's explicit Runge–Kutta pair of order
!> 8 with the embedded 5th- and 3rd-order error estimates and the 7th-order continuous extension,
!> as described by Hairer, Nørsett & Wanner (Solving ODEs I, 2nd ed., §II.5, §II.6, §II.10), with
!> their step-size control (error exponent 1/8, no PI term) and their initial-step heuristic.
!> Written here from the published method; the coefficients are in results_dop853_coefficients.
!>
!> Use: dop_init (state, tolerances, first step), then dop_step to take one accepted step (as many
!> rejections as the controller needs), dop_dense to build the continuous extension of that step,
!> dop_eval for y at any point of it, dop_restart after an impact map changed y (a one-step method
!> needs no history: the step size proposed before the impact is kept).
module results_dop853
  use, intrinsic :: iso_fortran_env, only: rk => real64
  use results_dop853_coefficients
  implicit none
  private

  abstract interface
    !> f = y'(t, y) of the first-order system.
    subroutine rhs_iface(t, y, f)
      import :: rk
      real(rk), intent(in) :: t, y(:)
      real(rk), intent(out) :: f(:)
    end subroutine rhs_iface
  end interface

  !> The integrator's state between steps and the last accepted step (for the dense output).
  type, public :: dop853_t
    integer :: n = 0
    real(rk) :: rtol = 1.0e-6_rk, atol = 1.0e-6_rk
    real(rk) :: t = 0.0_rk, h = 0.0_rk          !< current time, proposed next step
    real(rk) :: h_max = huge(1.0_rk)            !< largest step allowed (0 < h_max)
    real(rk) :: t_old = 0.0_rk, h_old = 0.0_rk  !< the last accepted step [t_old, t_old + h_old]
    real(rk), allocatable :: y(:), y_old(:)
    real(rk), allocatable :: k(:, :)            !< stage derivatives k(:, 1..16); k(:, 1) = f(t, y)
    real(rk), allocatable :: dense(:, :)        !< the continuous extension's vectors r_1..r_7
    logical :: dense_ready = .false.
    integer :: n_fev = 0, n_accepted = 0, n_rejected = 0
  end type dop853_t

  procedure(rhs_iface), pointer :: rhs => null()

  real(rk), parameter :: SAFETY = 0.9_rk, FAC_MIN = 0.333_rk, FAC_MAX = 6.0_rk

  public :: rhs_iface, dop_init, dop_step, dop_dense, dop_eval, dop_restart, dop_fixed_step

contains

  !> Start at (t0, y0); h0 > 0 is the first step, h0 <= 0 asks for the initial-step heuristic.
  subroutine dop_init(self, f, t0, y0, rtol, atol, h0)
    type(dop853_t), intent(inout) :: self
    procedure(rhs_iface) :: f
    real(rk), intent(in) :: t0, y0(:), rtol, atol, h0
    logical, save :: have_coefficients = .false.
    if (.not. have_coefficients) then
      call dop853_coefficients_init()
      have_coefficients = .true.
    end if
    rhs => f
    self%n = size(y0)
    self%rtol = rtol; self%atol = atol
    self%t = t0; self%y = y0; self%y_old = y0
    if (allocated(self%k)) deallocate (self%k)
    if (allocated(self%dense)) deallocate (self%dense)
    allocate (self%k(self%n, DOP_STAGES_DENSE), self%dense(self%n, 7))
    self%k = 0.0_rk; self%dense = 0.0_rk
    self%n_fev = 0; self%n_accepted = 0; self%n_rejected = 0
    call rhs(t0, y0, self%k(:, 1)); self%n_fev = self%n_fev + 1
    if (h0 > 0.0_rk) then
      self%h = h0
    else
      self%h = initial_step(self)
    end if
    self%h = min(self%h, self%h_max)
    self%dense_ready = .false.
  end subroutine dop_init

  !> The state changed at the current time (impact map): new derivative, same proposed step.
  subroutine dop_restart(self, y)
    type(dop853_t), intent(inout) :: self
    real(rk), intent(in) :: y(:)
    self%y = y
    call rhs(self%t, self%y, self%k(:, 1)); self%n_fev = self%n_fev + 1
    self%dense_ready = .false.
  end subroutine dop_restart

  !> Hairer's starting step: h0 from |y|/|f|, an explicit Euler step to estimate the second
  !> derivative, h1 = (0.01 / max(|f|, |y''|))^(1/8); the smaller of 100 h0 and h1.
  real(rk) function initial_step(self) result(h)
    type(dop853_t), intent(inout) :: self
    real(rk) :: sc(self%n), y1(self%n), f1(self%n), d0, d1, d2, h0, h1
    sc = self%atol + self%rtol * abs(self%y)
    d0 = rms(self%y / sc); d1 = rms(self%k(:, 1) / sc)
    if (d0 < 1.0e-5_rk .or. d1 < 1.0e-5_rk) then
      h0 = 1.0e-6_rk
    else
      h0 = 0.01_rk * d0 / d1
    end if
    h0 = min(h0, self%h_max)
    y1 = self%y + h0 * self%k(:, 1)
    call rhs(self%t + h0, y1, f1); self%n_fev = self%n_fev + 1
    d2 = rms((f1 - self%k(:, 1)) / sc) / h0
    if (max(d1, d2) <= 1.0e-15_rk) then
      h1 = max(1.0e-6_rk, h0 * 1.0e-3_rk)
    else
      h1 = (0.01_rk / max(d1, d2))**(1.0_rk / 8.0_rk)
    end if
    h = min(100.0_rk * h0, h1)
  end function initial_step

  pure real(rk) function rms(x)
    real(rk), intent(in) :: x(:)
    rms = sqrt(sum(x**2) / size(x))
  end function rms

  !> Stages 2..12 and the new state for step h from (t, y) with k(:, 1) = f(t, y); k(:, 13) =
  !> f(t + h, y_new) (the next step's first stage).
  subroutine stages(self, h, y_new)
    type(dop853_t), intent(inout) :: self
    real(rk), intent(in) :: h
    real(rk), intent(out) :: y_new(:)
    real(rk) :: ys(self%n)
    integer :: i, j
    do i = 2, DOP_STAGES
      ys = self%y
      do j = 1, i - 1
        if (dop_a(i, j) /= 0.0_rk) ys = ys + (h * dop_a(i, j)) * self%k(:, j)
      end do
      call rhs(self%t + dop_c(i) * h, ys, self%k(:, i))
    end do
    y_new = self%y
    do j = 1, DOP_STAGES
      if (dop_a(DOP_STAGES + 1, j) /= 0.0_rk) y_new = y_new + (h * dop_a(DOP_STAGES + 1, j)) * self%k(:, j)
    end do
    call rhs(self%t + h, y_new, self%k(:, DOP_STAGES + 1))
    self%n_fev = self%n_fev + DOP_STAGES
  end subroutine stages

  !> One step of size h without error control (for the order check); the dense output is then
  !> available for it as after dop_step.
  subroutine dop_fixed_step(self, h)
    type(dop853_t), intent(inout) :: self
    real(rk), intent(in) :: h
    real(rk) :: y_new(self%n)
    call stages(self, h, y_new)
    call accept(self, h, y_new)
  end subroutine dop_fixed_step

  subroutine accept(self, h, y_new)
    type(dop853_t), intent(inout) :: self
    real(rk), intent(in) :: h, y_new(:)
    self%t_old = self%t; self%h_old = h; self%y_old = self%y
    self%t = self%t + h
    self%y = y_new
    self%k(:, 14) = self%k(:, 1)   ! f at the step's start, kept for dop_dense (stage 14 is built there)
    self%k(:, 1) = self%k(:, DOP_STAGES + 1)
    self%dense_ready = .false.
    self%n_accepted = self%n_accepted + 1
  end subroutine accept

  !> One accepted step, not beyond t_stop (> t). ok = .false. when the step size underflows or the
  !> state stops being finite (the caller reports it).
  subroutine dop_step(self, t_stop, ok)
    type(dop853_t), intent(inout) :: self
    real(rk), intent(in) :: t_stop
    logical, intent(out) :: ok
    real(rk) :: h, err, fac, y_new(self%n), h_proposed
    logical :: last, rejected
    rejected = .false.
    ok = .false.
    do
      h = min(self%h, self%h_max)
      h_proposed = h
      last = self%t + h >= t_stop
      if (last) h = t_stop - self%t
      if (.not. h > 10.0_rk * epsilon(1.0_rk) * abs(self%t)) return
      call stages(self, h, y_new)
      if (.not. all(abs(y_new) <= huge(1.0_rk))) then
        err = huge(1.0_rk)
      else
        err = error_norm(self, h, y_new)
      end if
      fac = min(FAC_MAX, max(FAC_MIN, SAFETY * max(err, 1.0e-30_rk)**(-1.0_rk / 8.0_rk)))
      if (err <= 1.0_rk) then
        if (rejected) fac = min(fac, 1.0_rk)
        call accept(self, h, y_new)
        if (last) self%t = t_stop
        self%h = h * fac
        if (last) self%h = max(self%h, h_proposed)   ! a step cut short by t_stop: keep the proposal
        ok = .true.
        return
      end if
      rejected = .true.
      self%n_rejected = self%n_rejected + 1
      self%h = h * fac
    end do
  end subroutine dop_step

  !> Hairer's error measure of DOP853: the 5th-order estimate, scaled down where the 3rd-order
  !> one is small compared with it, in the RMS norm with sc = atol + rtol max(|y|, |y_new|).
  real(rk) function error_norm(self, h, y_new) result(err)
    type(dop853_t), intent(in) :: self
    real(rk), intent(in) :: h, y_new(:)
    real(rk) :: sc(self%n), e3(self%n), e5(self%n), s3, s5, deno
    integer :: j
    sc = self%atol + self%rtol * max(abs(self%y), abs(y_new))
    e3 = 0.0_rk; e5 = 0.0_rk
    do j = 1, DOP_STAGES
      if (dop_e3(j) /= 0.0_rk) e3 = e3 + dop_e3(j) * self%k(:, j)
      if (dop_e5(j) /= 0.0_rk) e5 = e5 + dop_e5(j) * self%k(:, j)
    end do
    s3 = sum((e3 / sc)**2); s5 = sum((e5 / sc)**2)
    deno = s5 + 0.01_rk * s3
    if (deno <= 0.0_rk) deno = 1.0_rk
    err = abs(h) * s5 / sqrt(deno * self%n)
  end function error_norm

  !> The continuous extension of the last accepted step: three more stages (c = 0.1, 0.2, 7/9) and
  !> the vectors r_1..r_7 of Hairer's form
  !>   y(t_old + x h) = y_old + x (r1 + (1-x) (r2 + x (r3 + (1-x) (r4 + x (r5 + (1-x) (r6 + x r7)))))).
  !> The step's stages are still in k(:, 2..12), f(t_old, y_old) in k(:, 14), f(t, y) in k(:, 1).
  subroutine dop_dense(self)
    type(dop853_t), intent(inout) :: self
    real(rk) :: kk(self%n, DOP_STAGES_DENSE), ys(self%n), dy(self%n), h
    integer :: i, j
    if (self%dense_ready) return
    h = self%h_old
    kk(:, 1) = self%k(:, 14)                    ! f at the step's start
    kk(:, 2:DOP_STAGES) = self%k(:, 2:DOP_STAGES)
    kk(:, DOP_STAGES + 1) = self%k(:, 1)        ! f at the step's end
    do i = DOP_STAGES + 2, DOP_STAGES_DENSE
      ys = self%y_old
      do j = 1, i - 1
        if (dop_a(i, j) /= 0.0_rk) ys = ys + (h * dop_a(i, j)) * kk(:, j)
      end do
      call rhs(self%t_old + dop_c(i) * h, ys, kk(:, i))
    end do
    self%n_fev = self%n_fev + 3
    dy = self%y - self%y_old
    self%dense(:, 1) = dy
    self%dense(:, 2) = h * kk(:, 1) - dy
    self%dense(:, 3) = dy - h * kk(:, DOP_STAGES + 1) - self%dense(:, 2)
    do i = 1, 4
      self%dense(:, 3 + i) = 0.0_rk
      do j = 1, DOP_STAGES_DENSE
        if (dop_d(i, j) /= 0.0_rk) self%dense(:, 3 + i) = self%dense(:, 3 + i) + (h * dop_d(i, j)) * kk(:, j)
      end do
    end do
    self%dense_ready = .true.
  end subroutine dop_dense

  !> y at t_old + x h_old of the last accepted step, 0 <= x <= 1 (dop_dense first).
  subroutine dop_eval(self, x, y)
    type(dop853_t), intent(in) :: self
    real(rk), intent(in) :: x
    real(rk), intent(out) :: y(:)
    real(rk) :: x1
    x1 = 1.0_rk - x
    y = self%dense(:, 6) + x * self%dense(:, 7)
    y = self%dense(:, 5) + x1 * y
    y = self%dense(:, 4) + x * y
    y = self%dense(:, 3) + x1 * y
    y = self%dense(:, 2) + x * y
    y = self%dense(:, 1) + x1 * y
    y = self%y_old + x * y
  end subroutine dop_eval
end module results_dop853
