!> The initialisation's check of a model's sparse Hessian callback (hessians_sparse, with a declared
!> pattern): its three blocks against central differences of the model's gradients dl_dq and dl_dv,
!> column by column, at the start (q, v) and at two points near it (as the band check does), so
!> that a wrong value, or a nonzero the declared pattern leaves out, is a status with the entry
!> named at initialisation rather than a Newton matrix silently wrong for the whole run. Cost, once
!> per initialisation: 18 n calls of dl_dq or dl_dv and 3 of hessians_sparse, O(n + nnz) memory
!> (no n x n array: the point of hessians_sparse).
module vci_sparse_hessian_check
  use vci_kinds, only: dp
  use vci_status, only: VCI_OK, VCI_ERR_ARGUMENT, VCI_ERR_CALLBACK, VCI_ERR_MEMORY, VCI_ERR_NONFINITE
  use vci_sparse, only: vci_sparse_pattern_t
  use vci_lagrangian, only: vci_lagrangian_t, vci_lagrangian_work_t, lagrangian_sparse_setup, &
                            lagrangian_sparse_hessians, check_point
  implicit none
  private

  public :: lagrangian_check_sparse

  ! relative difference step (~ eps^(1/3): central differences) and the agreement asked of them
  real(dp), parameter :: fd_rel = 6.0e-6_dp, fd_tol = 1.0e-6_dp

contains

  !> Check lag's hessians_sparse (when it supplies one, with a declared pattern of n columns, no
  !> band and no per-matrix debug check) at (q, v) and two nearby points. stat: VCI_OK (also when
  !> there is nothing to check); VCI_ERR_ARGUMENT: a value off by more than 1e-6 of the block's
  !> largest entry, or such an entry outside the pattern (why names it, and the point);
  !> VCI_ERR_CALLBACK / VCI_ERR_NONFINITE: hessians_sparse, dl_dq or dl_dv failed or gave NaN/Inf;
  !> VCI_ERR_MEMORY.
  subroutine lagrangian_check_sparse(lag, q, v, why, stat)
    class(vci_lagrangian_t), intent(inout) :: lag
    real(dp), intent(in) :: q(:), v(:)
    character(len=*), intent(out) :: why
    integer, intent(out) :: stat
    type(vci_lagrangian_work_t) :: work
    real(dp), allocatable :: qk(:), vk(:), x(:), y(:), fp(:), fm(:), gp(:), gm(:), col(:, :)
    character(len=3), parameter :: names(3) = ['qq', 'qv', 'vv']
    real(dp) :: scale(3), d, tol
    integer :: n, k, i, j, b, p, s
    why = ''
    stat = VCI_OK
    n = size(q)
    associate (pat => lag%hessian_pattern)
      if (pat%n /= n .or. n < 1 .or. lag%hessian_bandwidth >= 0 .or. lag%check_pattern) return
      allocate (qk(n), vk(n), x(n), y(n), fp(n), fm(n), gp(n), gm(n), col(n, 3), stat=s)
      if (s == 0) call lagrangian_sparse_setup(work, pat, s)
      if (s /= 0) then
        why = 'cannot allocate the check of the sparse Hessians (out of memory)'
        stat = VCI_ERR_MEMORY; return
      end if
      call lag%clear_not_provided(); s = 0
      call lag%hessians_sparse(q, v, work%uqq, work%uqv, work%uvv, s)
      if (lag%answered_not_provided()) then        ! no sparse callback: nothing to check
        call lag%clear_not_provided(); return
      end if
      call lag%clear_not_provided()
      do k = 0, 2
        call check_point(q, v, k, qk, vk)     ! (q, v), then two points near it (the band check's)
        call lagrangian_sparse_hessians(lag, work, pat, qk, vk, work%sqq, work%sqv, work%svv, stat)
        if (stat /= VCI_OK) then
          why = 'hessians_sparse failed or returned NaN/Inf in the check of the sparse Hessians'
          return
        end if
        scale(1) = max(1.0_dp, maxval(abs(work%sqq)))
        scale(2) = max(1.0_dp, maxval(abs(work%sqv)))
        scale(3) = max(1.0_dp, maxval(abs(work%svv)))
        do j = 1, n
          ! column j of L_qq from dl_dq at q -+ d e_j; of L_qv (d2L/dq_i dv_j) and L_vv from dl_dq
          ! and dl_dv at v -+ d e_j
          x = qk
          d = fd_rel * max(abs(qk(j)), 1.0_dp)
          x(j) = qk(j) + d
          call gradient(x, vk, fp, 1)
          x(j) = qk(j) - d
          if (stat == VCI_OK) call gradient(x, vk, fm, 1)
          if (stat /= VCI_OK) return
          col(:, 1) = (fp - fm) / (2.0_dp * d)
          y = vk
          d = fd_rel * max(abs(vk(j)), 1.0_dp)
          y(j) = vk(j) + d
          call gradient(qk, y, fp, 1)
          if (stat == VCI_OK) call gradient(qk, y, gp, 2)
          y(j) = vk(j) - d
          if (stat == VCI_OK) call gradient(qk, y, fm, 1)
          if (stat == VCI_OK) call gradient(qk, y, gm, 2)
          if (stat /= VCI_OK) return
          col(:, 2) = (fp - fm) / (2.0_dp * d)
          col(:, 3) = (gp - gm) / (2.0_dp * d)
          do b = 1, 3
            tol = fd_tol * max(scale(b), maxval(abs(col(:, b))))
            p = pat%colptr(j)
            do i = 1, n
              if (p < pat%colptr(j + 1)) then
                if (pat%rowind(p) == i) then
                  if (abs(given(b, p) - col(i, b)) > tol) then
                    write (why, '(a,i0,a,i0,a,es10.3,a,es10.3,a,i0,a)') 'hessians_sparse gives L_'// &
                      trim(names(b))//'(', i, ', ', j, ') = ', given(b, p), ' where central differences of '// &
                      'dl_dq and dl_dv give ', col(i, b), ' (point ', k, ' of the check of the sparse Hessians)'
                    stat = VCI_ERR_ARGUMENT; return
                  end if
                  p = p + 1; cycle
                end if
              end if
              if (abs(col(i, b)) > tol) then
                write (why, '(a,i0,a,i0,a,es10.3,a,i0,a)') 'L_'//trim(names(b))//'(', i, ', ', j, ') = ', col(i, b), &
                  ' (central differences of dl_dq and dl_dv) lies outside the declared sparse pattern (point ', k, &
                  ' of the check of the sparse Hessians)'
                stat = VCI_ERR_ARGUMENT; return
              end if
            end do
          end do
        end do
      end do
    end associate
  contains
    !> g = dl_dq (which = 1) or dl_dv (2) at (qq, vv); a failure sets stat and why.
    subroutine gradient(qq, vv, g, which)
      real(dp), intent(in) :: qq(:), vv(:)
      real(dp), intent(out) :: g(:)
      integer, intent(in) :: which
      integer :: st
      st = 0
      if (which == 1) then
        call lag%dl_dq(qq, vv, g, st)
      else
        call lag%dl_dv(qq, vv, g, st)
      end if
      if (st /= 0) then
        stat = VCI_ERR_CALLBACK
        why = 'dl_dq or dl_dv failed in the check of the sparse Hessians'
      else if (.not. (abs(sum(g)) <= huge(1.0_dp))) then
        stat = VCI_ERR_NONFINITE
        why = 'dl_dq or dl_dv returned NaN/Inf in the check of the sparse Hessians'
      end if
    end subroutine gradient
    real(dp) function given(b, p)
      integer, intent(in) :: b, p
      select case (b)
      case (1); given = work%sqq(p)
      case (2); given = work%sqv(p)
      case default; given = work%svv(p)
      end select
    end function given
  end subroutine lagrangian_check_sparse
end module vci_sparse_hessian_check
