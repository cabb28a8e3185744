;; verdict: error
;; message: empty
;; where: domain
;; line: none
; nothing but a comment
