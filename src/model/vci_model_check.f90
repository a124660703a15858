!> The model checker (issue 31): compares every derivative a model supplies with central differences
!> of the function it should be the derivative of, at one point (q, v, h), and reports the worst
!> relative mismatch per callback with a verdict. A wrong sign, a swapped or transposed Hessian block,
!> a wrong gap gradient otherwise run as wrong physics with status 0, or end in Newton failures far
!> from their cause.
!>
!> What is compared (D = central difference, step 6e-6 max(1, |x|)):
!>  - discrete L_d (no value of L_d is supplied, so its partials are checked against each other):
!>    D_v D1 = (D_q D2)^T (D1 and D2 partials of one function), D_q D3 = D_h D1 and D_v D3 = D_h D2,
!>    the mixed Hessian against D_v D1, the discrete constraint's Jacobian against D_other omega_d,
!>    the constraint forms against the discrete form (h D_other omega_d(q, q, h) = Omega(q)^T);
!>  - continuous L: dL/dq and dL/dqdot against D L, the Hessian blocks against D of dL/dq and
!>    dL/dqdot, H(q, dL/dqdot) against the Legendre transform dL/dqdot . qdot - L;
!>  - both: the gap gradients against D g.
!> Each mismatch is max_i |a_i - d_i| / max(max|a|, max|d|, floor): relative to the block's size, so a
!> block that is right except for round-off scores about 1e-9 and a wrong one about 1.
module vci_model_check
  use vci_kinds, only: dp
  use vci_status
  use vci_model_base, only: vci_model_base_t
  use vci_model, only: vci_model_t
  use vci_lagrangian, only: vci_lagrangian_t
  implicit none
  private

  integer, parameter, public :: VCI_CHECK_MAX_ITEMS = 16  !< the most comparisons a report holds
  !> Default verdict threshold: central differences of smooth callbacks agree to ~1e-9.
  real(dp), parameter, public :: VCI_CHECK_DEFAULT_TOL = 1.0e-6_dp

  !> One comparison: which callback, against what, its worst relative mismatch; `checked` false when
  !> the model does not supply that callback (the library then differences it itself).
  type, public :: vci_check_item_t
    character(len=32) :: name = ''      !< the callback checked
    character(len=64) :: against = ''   !< what it is compared with
    real(dp) :: mismatch = 0.0_dp       !< worst relative mismatch
    logical :: checked = .false.        !< false: the model does not supply this callback
  end type vci_check_item_t

  !> What vci_check_model found: one item per comparison, and the verdict against tol.
  type, public :: vci_check_report_t
    integer :: count = 0                            !< items filled
    type(vci_check_item_t) :: items(VCI_CHECK_MAX_ITEMS)  !< the comparisons, items(1:count)
    real(dp) :: tol = VCI_CHECK_DEFAULT_TOL         !< the verdict's threshold
    logical :: passed = .true.        !< every checked item within tol
    real(dp) :: worst = 0.0_dp        !< the largest mismatch of the checked items
  contains
    !> Item i as one line of text (name, against, mismatch, verdict).
    procedure :: line => report_line
  end type vci_check_report_t

  public :: vci_check_model

  real(dp), parameter :: fd_rel = 6.0e-6_dp   ! ~ eps**(1/3)

contains

  !> Check the model's derivatives at (q, v, h): v is the second configuration of L_d(q, v, h) for a
  !> discrete model, the velocity qdot for a continuous one (h is then unused). stat: VCI_OK when the
  !> check ran (the verdict is report%passed), VCI_ERR_ARGUMENT on wrong sizes or h <= 0,
  !> VCI_ERR_CALLBACK when a callback failed or returned NaN/Inf (msg names it).
  subroutine vci_check_model(model, q, v, h, report, stat, msg, tol)
    class(vci_model_base_t), intent(inout) :: model
    real(dp), intent(in) :: q(:), v(:), h
    type(vci_check_report_t), intent(out) :: report
    integer, intent(out) :: stat
    character(len=*), intent(out) :: msg
    real(dp), intent(in), optional :: tol
    integer :: i
    msg = ''
    if (present(tol)) report%tol = tol
    stat = VCI_ERR_ARGUMENT
    if (size(q) /= model%n .or. size(v) /= model%n) then
      msg = 'vci_check_model: q and v must have n entries'; return
    end if
    if (.not. (h > 0.0_dp .and. h <= huge(h)) .or. .not. (all(abs(q) <= huge(h)) .and. all(abs(v) <= huge(h)))) then
      msg = 'vci_check_model: q, v must be finite and h > 0'; return
    end if
    select type (model)
    class is (vci_model_t)
      call check_discrete(model, q, v, h, report, stat, msg)
    class is (vci_lagrangian_t)
      call check_continuous(model, q, v, report, stat, msg)
    class default
      msg = 'vci_check_model: the model is neither a discrete (vci_model_t) nor a continuous (vci_lagrangian_t) one'
      return
    end select
    if (stat == VCI_OK) call check_gaps(model, q, report, stat, msg)
    if (stat /= VCI_OK) return
    report%worst = 0.0_dp
    do i = 1, report%count
      if (report%items(i)%checked) report%worst = max(report%worst, report%items(i)%mismatch)
    end do
    report%passed = report%worst <= report%tol
  end subroutine vci_check_model

  !> The check's work arrays could not be allocated (the library never stops the program).
  subroutine out_of_memory(stat, msg)
    integer, intent(out) :: stat
    character(len=*), intent(inout) :: msg
    stat = VCI_ERR_MEMORY
    msg = 'vci_check_model: cannot allocate the work arrays of the check (out of memory)'
  end subroutine out_of_memory

  !> "name  against  mismatch  verdict" for item i (fixed length; trim it).
  function report_line(self, i) result(text)
    class(vci_check_report_t), intent(in) :: self
    integer, intent(in) :: i
    character(len=160) :: text
    associate (it => self%items(i))
      if (.not. it%checked) then
        write (text, '(a32,1x,a64,a)') it%name, it%against, '   not supplied'
      else
        write (text, '(a32,1x,a64,es10.2,a)') it%name, it%against, it%mismatch, &
          trim(merge('  ok      ', '  MISMATCH', it%mismatch <= self%tol))
      end if
    end associate
  end function report_line

  subroutine check_discrete(model, q, v, h, report, stat, msg)
    class(vci_model_t), intent(inout) :: model
    real(dp), intent(in) :: q(:), v(:), h
    type(vci_check_report_t), intent(inout) :: report
    integer, intent(out) :: stat
    character(len=*), intent(inout) :: msg
    integer :: n, m, j, s
    real(dp) :: dd, d3p, d3m, dh
    real(dp), allocatable :: qp(:), vp(:), fp(:), fm(:), j1(:, :), j2(:, :), hess(:, :), d3q(:), d3v(:), &
                             d1h(:), d2h(:), omega(:, :), jd(:, :), jfd(:, :), cp(:), cm(:)
    n = model%n; m = model%m
    allocate (qp(n), vp(n), fp(n), fm(n), j1(n, n), j2(n, n), hess(n, n), d3q(n), d3v(n), d1h(n), d2h(n), stat=s)
    if (s /= 0) then
      call out_of_memory(stat, msg); return
    end if
    stat = VCI_OK
    qp = q; vp = v
    do j = 1, n
      ! j1(:, j) = d D1 / d v_j ; j2(:, j) = d D2 / d q_j ; D3's partials along q_j, v_j
      dd = step(v(j)); vp(j) = v(j) + dd
      call d12(1, q, vp, h, fp)
      call d3(q, vp, h, d3p); vp(j) = v(j) - dd
      call d12(1, q, vp, h, fm); call d3(q, vp, h, d3m); vp(j) = v(j)
      if (stat /= VCI_OK) return
      j1(:, j) = (fp - fm) / (2 * dd); d3v(j) = (d3p - d3m) / (2 * dd)
      dd = step(q(j)); qp(j) = q(j) + dd
      call d12(2, qp, v, h, fp); call d3(qp, v, h, d3p); qp(j) = q(j) - dd
      call d12(2, qp, v, h, fm); call d3(qp, v, h, d3m); qp(j) = q(j)
      if (stat /= VCI_OK) return
      j2(:, j) = (fp - fm) / (2 * dd); d3q(j) = (d3p - d3m) / (2 * dd)
    end do
    dh = fd_rel * h   ! relative to h: L_d has terms in 1/h
    call d12(1, q, v, h + dh, fp); call d12(1, q, v, h - dh, fm); d1h = (fp - fm) / (2 * dh)
    call d12(2, q, v, h + dh, fp); call d12(2, q, v, h - dh, fm); d2h = (fp - fm) / (2 * dh)
    if (stat /= VCI_OK) return
    call add(report, 'd1, d2', 'D_v D1 = (D_q D2)^T (one L_d)', mismatch2(j1, transpose(j2)))
    call add(report, 'd3, d1', 'D_q D3 = D_h D1', mismatch(d3q, d1h))
    call add(report, 'd3, d2', 'D_v D3 = D_h D2', mismatch(d3v, d2h))
    call model%clear_not_provided(); s = 0
    call model%mixed_hessian(q, v, h, hess, s)
    if (model%answered_not_provided()) then
      call add(report, 'mixed_hessian', 'D_v D1', 0.0_dp, checked=.false.)
    else
      if (.not. ok(s, 'mixed_hessian', flat(hess))) return
      call add(report, 'mixed_hessian', 'D_v D1 and (D_q D2)^T', &
               max(mismatch2(hess, j1), mismatch2(hess, transpose(j2))))
    end if
    if (m == 0) return
    allocate (omega(n, m), jd(m, n), jfd(m, n), cp(m), cm(m), stat=s)
    if (s /= 0) then
      call out_of_memory(stat, msg); return
    end if
    ! the discrete form's Jacobian along `other`, differenced at (q, v) and at (q, q)
    call dconstraint_fd(v, jfd); if (stat /= VCI_OK) return
    call model%clear_not_provided(); s = 0
    call model%discrete_constraint_jacobian(q, v, h, jd, s)
    if (model%answered_not_provided()) then
      call add(report, 'discrete_constraint_jacobian', 'D_other omega_d', 0.0_dp, checked=.false.)
    else
      if (.not. ok(s, 'discrete_constraint_jacobian', flat(jd))) return
      call add(report, 'discrete_constraint_jacobian', 'D_other omega_d', mismatch2(jd, jfd))
    end if
    s = 0
    call model%constraint_forms(q, omega, s)
    if (.not. ok(s, 'constraint_forms', flat(omega))) return
    call dconstraint_fd(q, jfd); if (stat /= VCI_OK) return
    call add(report, 'constraint_forms, discrete', 'h D_other omega_d(q, q, h) = Omega(q)^T', &
             mismatch2(h * jfd, transpose(omega)))
  contains
    subroutine d12(which, a, b, hh, out)
      integer, intent(in) :: which
      real(dp), intent(in) :: a(:), b(:), hh
      real(dp), intent(out) :: out(:)
      integer :: s
      if (stat /= VCI_OK) return
      s = 0
      if (which == 1) then
        call model%d1(a, b, hh, out, s)
        if (.not. ok(s, 'd1', out)) return
      else
        call model%d2(a, b, hh, out, s)
        if (.not. ok(s, 'd2', out)) return
      end if
    end subroutine d12
    subroutine d3(a, b, hh, out)
      real(dp), intent(in) :: a(:), b(:), hh
      real(dp), intent(out) :: out
      integer :: s
      out = 0.0_dp
      if (stat /= VCI_OK) return
      s = 0
      call model%d3(a, b, hh, out, s)
      if (.not. ok(s, 'd3', [out])) return
    end subroutine d3
    subroutine dconstraint_fd(other, jac)
      real(dp), intent(in) :: other(:)
      real(dp), intent(out) :: jac(:, :)
      integer :: k, s
      real(dp) :: dk
      vp = other
      do k = 1, n
        dk = step(other(k))
        vp(k) = other(k) + dk; s = 0
        call model%discrete_constraint(q, vp, h, cp, s)
        if (.not. ok(s, 'discrete_constraint', cp)) return
        vp(k) = other(k) - dk
        call model%discrete_constraint(q, vp, h, cm, s)
        if (.not. ok(s, 'discrete_constraint', cm)) return
        vp(k) = other(k)
        jac(:, k) = (cp - cm) / (2 * dk)
      end do
    end subroutine dconstraint_fd
    logical function ok(s, name, vals)
      integer, intent(in) :: s
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: vals(:)
      ok = callback_ok(s, name, vals, stat, msg)
    end function ok
  end subroutine check_discrete

  subroutine check_continuous(model, q, v, report, stat, msg)
    class(vci_lagrangian_t), intent(inout) :: model
    real(dp), intent(in) :: q(:), v(:)
    type(vci_check_report_t), intent(inout) :: report
    integer, intent(out) :: stat
    character(len=*), intent(inout) :: msg
    integer :: n, j, s
    real(dp) :: dd, lp, lm, l0, e
    real(dp), allocatable :: qp(:), vp(:), lq(:), lv(:), fdq(:), fdv(:), fp(:), fm(:), &
                             hqq(:, :), hqv(:, :), hvv(:, :), aqq(:, :), aqv(:, :), avv(:, :)
    n = model%n
    allocate (qp(n), vp(n), lq(n), lv(n), fdq(n), fdv(n), fp(n), fm(n), hqq(n, n), hqv(n, n), hvv(n, n), &
              aqq(n, n), aqv(n, n), avv(n, n), stat=s)
    if (s /= 0) then
      call out_of_memory(stat, msg); return
    end if
    stat = VCI_OK
    s = 0; call model%lagrangian(q, v, l0, s); if (.not. ok(s, 'lagrangian', [l0])) return
    s = 0; call model%dl_dq(q, v, lq, s); if (.not. ok(s, 'dl_dq', lq)) return
    s = 0; call model%dl_dv(q, v, lv, s); if (.not. ok(s, 'dl_dv', lv)) return
    qp = q; vp = v
    do j = 1, n
      dd = step(q(j))
      qp(j) = q(j) + dd; s = 0; call model%lagrangian(qp, v, lp, s); if (.not. ok(s, 'lagrangian', [lp])) return
      s = 0; call model%dl_dq(qp, v, fp, s); if (.not. ok(s, 'dl_dq', fp)) return
      qp(j) = q(j) - dd; s = 0; call model%lagrangian(qp, v, lm, s); if (.not. ok(s, 'lagrangian', [lm])) return
      s = 0; call model%dl_dq(qp, v, fm, s); if (.not. ok(s, 'dl_dq', fm)) return
      qp(j) = q(j)
      fdq(j) = (lp - lm) / (2 * dd); hqq(:, j) = (fp - fm) / (2 * dd)
      dd = step(v(j))
      vp(j) = v(j) + dd; s = 0; call model%lagrangian(q, vp, lp, s); if (.not. ok(s, 'lagrangian', [lp])) return
      s = 0; call model%dl_dq(q, vp, fp, s); if (.not. ok(s, 'dl_dq', fp)) return
      s = 0; call model%dl_dv(q, vp, lq, s); if (.not. ok(s, 'dl_dv', lq)) return
      hvv(:, j) = lq
      vp(j) = v(j) - dd; s = 0; call model%lagrangian(q, vp, lm, s); if (.not. ok(s, 'lagrangian', [lm])) return
      s = 0; call model%dl_dq(q, vp, fm, s); if (.not. ok(s, 'dl_dq', fm)) return
      s = 0; call model%dl_dv(q, vp, lq, s); if (.not. ok(s, 'dl_dv', lq)) return
      vp(j) = v(j)
      fdv(j) = (lp - lm) / (2 * dd); hqv(:, j) = (fp - fm) / (2 * dd); hvv(:, j) = (hvv(:, j) - lq) / (2 * dd)
    end do
    s = 0; call model%dl_dq(q, v, lq, s)
    call add(report, 'dl_dq', 'D_q L', mismatch(lq, fdq))
    call add(report, 'dl_dv', 'D_qdot L', mismatch(lv, fdv))
    call model%clear_not_provided(); s = 0
    call model%hessians(q, v, aqq, aqv, avv, s)
    if (model%answered_not_provided()) then
      call add(report, 'hessians', 'D of dl_dq, dl_dv', 0.0_dp, checked=.false.)
    else
      if (.not. ok(s, 'hessians', flat(aqq))) return
      if (.not. ok(s, 'hessians', flat(aqv))) return
      if (.not. ok(s, 'hessians', flat(avv))) return
      call add(report, 'hessians: lqq', 'D_q dl_dq', mismatch2(aqq, hqq))
      call add(report, 'hessians: lqv', 'D_qdot dl_dq', mismatch2(aqv, hqv))
      call add(report, 'hessians: lvv', 'D_qdot dl_dv', mismatch2(avv, hvv))
    end if
    call model%clear_not_provided(); s = 0
    call model%energy(q, lv, e, s)
    if (model%answered_not_provided()) then
      call add(report, 'energy', 'dl_dv . qdot - L', 0.0_dp, checked=.false.)
    else
      if (.not. ok(s, 'energy', [e])) return
      call add(report, 'energy', 'H(q, dl_dv) = dl_dv . qdot - L', &
               mismatch([e], [dot_product(lv, v) - l0], floor=abs(l0)))
    end if
  contains
    logical function ok(s, name, vals)
      integer, intent(in) :: s
      character(len=*), intent(in) :: name
      real(dp), intent(in) :: vals(:)
      ok = callback_ok(s, name, vals, stat, msg)
    end function ok
  end subroutine check_continuous

  subroutine check_gaps(model, q, report, stat, msg)
    class(vci_model_base_t), intent(inout) :: model
    real(dp), intent(in) :: q(:)
    type(vci_check_report_t), intent(inout) :: report
    integer, intent(out) :: stat
    character(len=*), intent(inout) :: msg
    integer :: n, ng, j, s
    real(dp) :: dd
    real(dp), allocatable :: qp(:), gp(:), gm(:), dg(:, :), fd(:, :)
    stat = VCI_OK
    n = model%n; ng = model%n_gaps
    if (ng == 0) return
    allocate (qp(n), gp(ng), gm(ng), dg(n, ng), fd(n, ng), stat=s)
    if (s /= 0) then
      call out_of_memory(stat, msg); return
    end if
    qp = q
    do j = 1, n
      dd = step(q(j))
      qp(j) = q(j) + dd; s = 0; call model%gaps(qp, gp, s)
      if (.not. callback_ok(s, 'gaps', gp, stat, msg)) return
      qp(j) = q(j) - dd; s = 0; call model%gaps(qp, gm, s)
      if (.not. callback_ok(s, 'gaps', gm, stat, msg)) return
      qp(j) = q(j)
      fd(j, :) = (gp - gm) / (2 * dd)
    end do
    call model%clear_not_provided(); s = 0
    call model%gap_gradients(q, dg, s)
    if (model%answered_not_provided()) then
      call add(report, 'gap_gradients', 'D_q g', 0.0_dp, checked=.false.)
    else
      if (.not. callback_ok(s, 'gap_gradients', flat(dg), stat, msg)) return
      ! per wall: each gradient relative to its own size
      dd = 0.0_dp
      do j = 1, ng
        dd = max(dd, mismatch(dg(:, j), fd(:, j)))
      end do
      call add(report, 'gap_gradients', 'D_q g (each wall)', dd)
    end if
  end subroutine check_gaps

  logical function callback_ok(s, name, vals, stat, msg)
    integer, intent(in) :: s
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: vals(:)
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: msg
    callback_ok = s == 0 .and. all(abs(vals) <= huge(1.0_dp))
    if (callback_ok) return
    stat = VCI_ERR_CALLBACK
    msg = 'vci_check_model: callback '//name//' failed or returned NaN/Inf at the point checked'
  end function callback_ok

  subroutine add(report, name, against, value, checked)
    type(vci_check_report_t), intent(inout) :: report
    character(len=*), intent(in) :: name, against
    real(dp), intent(in) :: value
    logical, intent(in), optional :: checked
    if (report%count >= VCI_CHECK_MAX_ITEMS) return
    report%count = report%count + 1
    report%items(report%count) = vci_check_item_t(name, against, value, .true.)
    if (present(checked)) report%items(report%count)%checked = checked
  end subroutine add

  pure real(dp) function step(x)
    real(dp), intent(in) :: x
    step = fd_rel * max(1.0_dp, abs(x))
  end function step

  !> max |a - b| relative to the larger of the two blocks (and floor): ~1e-9 when they agree.
  pure real(dp) function mismatch(a, b, floor)
    real(dp), intent(in) :: a(:), b(:)
    real(dp), intent(in), optional :: floor
    real(dp) :: size_ab
    size_ab = max(maxval(abs(a)), maxval(abs(b)))
    if (present(floor)) size_ab = max(size_ab, floor)
    ! a block that is zero in both (up to difference noise) agrees
    if (size_ab <= 1.0e-9_dp) then
      mismatch = 0.0_dp
    else
      mismatch = maxval(abs(a - b)) / size_ab
    end if
  end function mismatch

  pure function flat(a) result(v)
    real(dp), intent(in) :: a(:, :)
    real(dp) :: v(size(a))
    v = reshape(a, [size(a)])
  end function flat

  pure real(dp) function mismatch2(a, b)
    real(dp), intent(in) :: a(:, :), b(:, :)
    mismatch2 = mismatch(reshape(a, [size(a)]), reshape(b, [size(b)]))
  end function mismatch2
end module vci_model_check
