/* The controller FMU's model: its variables' values, and the C kernel's sensors and controller
 * (c_kernel/) that the scene runner's compiled loop runs, stepped once per communication
 * point. No FMI here: controller_fmu_model.c is the interface around it. */
#ifndef GIMBAL_CONTROLLER_MODEL_H
#define GIMBAL_CONTROLLER_MODEL_H

#include <stddef.h>

#include "controller_variables.h"
#include "gimbal_kernel/controllers.h"
#include "gimbal_kernel/sensors.h"

typedef struct {
    double real[REAL_COUNT];
    int integer[INTEGER_COUNT];
    int boolean[BOOLEAN_COUNT];
    GimbalSensors sensors;       /* from the parameters, by controller_model_start */
    GimbalController controller;
    double target[3];            /* unit vector in G */
    long step;                   /* the communication point the next step computes */
    int started;                 /* 1 from controller_model_start on: the model is initialized */
} ControllerModel;

/* Every variable at its start value, the kernel's state cleared. */
void controller_model_reset(ControllerModel* model);

/* 1 when the parameters can run; else 0 and `message` names the parameter and says why. */
int controller_model_check(const ControllerModel* model, char* message, size_t size);

/* The kernel's sensors and controller from the (checked) parameters, at rest: communication point 0 next. */
void controller_model_start(ControllerModel* model);

/* Communication point `model->step` with step h: the sensors read the inputs, the controller
 * computes the voltages and set points into the outputs. 1; 2 when a moving target's inputs gave no
 * direction to point at, and the step held the measured angles instead (`message` says which and why). */
int controller_model_step(ControllerModel* model, double h, char* message, size_t size);

#endif
