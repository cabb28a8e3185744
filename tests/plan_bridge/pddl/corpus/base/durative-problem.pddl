(define (problem deliver-one) (:domain courier)
  (:objects van - robot depot shop - place)
  (:init (at van depot) (link depot shop) (= (distance depot shop) 4) (= (travelled van) 0))
  (:goal (at van shop)))
