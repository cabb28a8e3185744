(define (problem inspect-ridge)
  (:domain timed-rover)
  (:objects
    rv - rover
    base ridge crater - site)
  (:init
    (parked rv base)
    (station base)
    (route base ridge) (route ridge base)
    (route ridge crater) (route crater ridge)
    (= (distance base ridge) 10) (= (distance ridge base) 10)
    (= (distance ridge crater) 8) (= (distance crater ridge) 8)
    (= (distance base crater) 30) (= (distance crater base) 30)
    (= (speed rv) 2)
    (= (energy rv) 40))
  (:goal (and (inspected ridge) (inspected crater) (parked rv base))))
